"""Search over designs and run a study: the design points, Pareto dominance, NSGA-II, the campaign backends, :func:`run_design`.

**Design points**: the references, the grid, and the seeds and run indices of every evaluation.

Run indices: the references first (0..R-1), then the grid in C order (architecture slowest, then
the swept parameters in :data:`~qprr.design.spec.PARAMETERS` order, each only where it applies);
with NSGA-II, architecture ``a`` generation ``g`` member ``k`` is run ``R + (a * generations + g) *
population + k`` (an architecture to which no ranged parameter applies is one design, and the
blocks after it start earlier).  Every design is measured with the same seed,
drawn from ``SeedSequence(seed)`` (the workspace estimator's counting-grid shifts): common random
numbers, so that two designs differ by their geometry, never by the shifts (two identical
geometries give identical numbers).  The table depends on the study only.

**Pareto dominance**, non-dominated sorting and the 2-D hypervolume, in minimisation form.

**NSGA-II** from a well-kept library, driven by ask/tell so that the campaign backends evaluate.

Two engines behind one interface (:class:`Optimiser`): pymoo's ``NSGA2`` (default) and Optuna's
``NSGAIISampler``.  Each generation is asked as a whole (``population`` points in [low, high]),
evaluated in parallel elsewhere, and told back in the order asked, so that a seeded study gives
the same designs whatever the backend, the number of workers or the order evaluations finish.
Constraints are told as violations (<= 0 feasible); a failed evaluation is told as infeasible with
the worst objective values.  Both packages are optional: pymoo is the extra ``qprr[design]`` (chosen by
measurement, docs/design.md), Optuna is installed apart (``pip install optuna``).

**The campaign package**: the design search uses its public API only, here (and its flight metrics in the report).

Backends (:func:`qprr.campaign.make_backend`: local process pool, Dask, inline), the session a
campaign runs in (:class:`qprr.campaign.session.Session`: the results store, CSV/Parquet appended as
rows arrive, fingerprint checked on resume, a lock per file; the progress line; the backend opened
at the first task and released in order), and the reader (:func:`qprr.campaign.read_results`).  The closed-loop check
(:mod:`qprr.design.report`) keeps the flight metrics of :func:`qprr.campaign.metrics_of`.

**Running a study**: evaluate its designs on a campaign backend, save each row as it arrives, resume.

:func:`run_design` evaluates the references and the grid, or, with ``search.method = "nsga2"``,
one NSGA-II per architecture over the ranged parameters, generation by generation (every
architecture's generation is submitted at once, so the workers stay busy).  Rows go to a campaign
results file (CSV/Parquet) the moment they arrive.  Running
the same study to the same file again resumes: the saved rows are read back, the optimisers are
replayed (same seed, same told values, so the same designs are asked again) and only the missing
designs are evaluated.
"""

from __future__ import annotations

import functools
import math
import time
import warnings
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..campaign import Backend, Results, make_backend, read_results
from ..campaign.metrics import RunStatus
from ..campaign.session import BackendChoice, Session
from ..errors import InputError, MissingDependencyError
from .evaluate import ID_COLUMNS, TAIL_COLUMNS, applies, cells, columns, evaluate_design, exclusions
from .metrics import DESIGN_METRICS, sign
from .spec import DesignSpec


# ---------------------------------------------------------------------------------------------- Design points
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


def candidates(spec: DesignSpec, family: str) -> list[dict]:
    """Every combination of the listed values (a fixed one is a list of one) of the parameters that apply to a candidate
    of ``family``, in order (the first parameter slowest); a parameter that does not apply is left out, not varied
    (:func:`~qprr.design.evaluate.applies`).  The ranged parameters are the optimiser's."""
    out: list[dict] = [{}]
    for k, p in spec.parameters.items():
        if p.optimised:
            continue
        grown = []
        for c in out:
            grown += [{**c, k: v} for v in p.values] if applies(spec, family, k, c) else [c]
        out = grown
    return out


def grid_points(spec: DesignSpec) -> list[dict]:
    """Every family (architecture, or the URDF study's robot) x every combination of the values that apply to it
    (after the references)."""
    out = []
    i = len(spec.references)
    for family in spec.families:
        for params in candidates(spec, family):
            out.append(point(spec, i, "grid", family, params))
            i += 1
    return out


def ranged(spec: DesignSpec, family: str) -> tuple[str, ...]:
    """The ranged parameters NSGA-II varies for ``family`` (those that apply to it)."""
    base = candidates(spec, family)[0]
    return tuple(k for k in spec.optimised if applies(spec, family, k, base))


def block_starts(spec: DesignSpec) -> list[int]:
    """NSGA-II: the first run of each family's block (``generations x population`` designs, or one design for a
    family to which no ranged parameter applies)."""
    s = spec.search
    starts, i = [], len(spec.references)
    for family in spec.families:
        starts.append(i)
        i += s.generations * s.population if ranged(spec, family) else 1
    return starts


def n_points(spec: DesignSpec) -> int:
    """How many designs the study evaluates."""
    if spec.search.method == "grid":
        return len(spec.references) + len(grid_points(spec))
    last = spec.families[-1]
    s = spec.search
    return block_starts(spec)[-1] + (s.generations * s.population if ranged(spec, last) else 1)


# ------------------------------------------------------------------------------------------- Pareto dominance
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


# ---------------------------------------------------------------------------------------------------- NSGA-II
INSTALL = {"pymoo": "pip install 'qprr[design]' (or pip install pymoo)", "optuna": "pip install optuna"}
"""Install command of each engine: pymoo is the ``design`` extra (docs/design.md says why), Optuna the alternative."""


class Optimiser(ABC):
    """Ask a generation of points (``(population, n_var)`` in the box), tell their objectives (to minimise) and violations."""

    def __init__(self, low, high, n_obj: int, n_constr: int, population: int, seed: int) -> None:
        self.low, self.high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
        if self.low.shape != self.high.shape or not np.all(self.low < self.high):
            raise InputError(f"optimiser bounds: low {self.low.tolist()} must be below high {self.high.tolist()} elementwise")
        self.n_obj, self.n_constr, self.population, self.seed = n_obj, n_constr, population, seed

    @abstractmethod
    def ask(self) -> np.ndarray: ...

    @abstractmethod
    def tell(self, F: np.ndarray, G: np.ndarray) -> None: ...


class PymooNSGA2(Optimiser):
    """pymoo's NSGA2 (``pymoo.algorithms.moo.nsga2``) through its ask/tell interface."""

    def __init__(self, low, high, n_obj, n_constr, population, seed) -> None:
        super().__init__(low, high, n_obj, n_constr, population, seed)
        try:
            from pymoo.algorithms.moo.nsga2 import NSGA2
            from pymoo.core.evaluator import Evaluator
            from pymoo.core.problem import Problem
            from pymoo.problems.static import StaticProblem
        except ImportError as exc:
            raise MissingDependencyError("pymoo", 'the NSGA-II design search (search.optimiser = "pymoo")', INSTALL["pymoo"]) from exc
        self._static, self._evaluator = StaticProblem, Evaluator
        self._problem = Problem(n_var=len(self.low), n_obj=n_obj, n_ieq_constr=max(n_constr, 1), xl=self.low, xu=self.high)
        self._alg = NSGA2(pop_size=population)
        self._alg.setup(self._problem, termination=("n_gen", 10**9), seed=seed, verbose=False)
        self._pop = None

    def ask(self) -> np.ndarray:
        self._pop = self._alg.ask()
        return np.array(self._pop.get("X"), dtype=float)

    def tell(self, F, G) -> None:
        G = np.asarray(G, dtype=float).reshape(len(F), -1) if self.n_constr else np.zeros((len(F), 1))
        self._evaluator().eval(self._static(self._problem, F=np.asarray(F, dtype=float), G=G), self._pop)
        self._alg.tell(infills=self._pop)


class OptunaNSGA2(Optimiser):
    """Optuna's ``NSGAIISampler`` through ``study.ask`` / ``study.tell``."""

    def __init__(self, low, high, n_obj, n_constr, population, seed) -> None:
        super().__init__(low, high, n_obj, n_constr, population, seed)
        try:
            import optuna
        except ImportError as exc:
            raise MissingDependencyError("optuna", 'the NSGA-II design search (search.optimiser = "optuna")', INSTALL["optuna"]) from exc
        optuna.logging.set_verbosity(optuna.logging.WARNING)
        cons = _violations if n_constr else None
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # constraints_func is flagged experimental
            sampler = optuna.samplers.NSGAIISampler(population_size=population, seed=seed, constraints_func=cons)
        self._study = optuna.create_study(directions=["minimize"] * n_obj, sampler=sampler)
        self._trials = []

    def ask(self) -> np.ndarray:
        self._trials = [self._study.ask() for _ in range(self.population)]
        return np.array([[t.suggest_float(f"x{i}", lo, hi) for i, (lo, hi) in enumerate(zip(self.low, self.high))] for t in self._trials])

    def tell(self, F, G) -> None:
        for t, f, g in zip(self._trials, np.asarray(F, dtype=float), np.asarray(G, dtype=float).reshape(len(F), -1)):
            t.set_user_attr("violation", [float(x) for x in g])
            self._study.tell(t, [float(x) for x in f])


def _violations(trial) -> list[float]:
    return trial.user_attrs["violation"]


ENGINES = {"pymoo": PymooNSGA2, "optuna": OptunaNSGA2}


def make_optimiser(name: str, low, high, n_obj: int, n_constr: int, population: int, seed: int) -> Optimiser:
    """An NSGA-II :class:`Optimiser` of engine ``name`` ("pymoo" or "optuna")."""
    if name not in ENGINES:
        raise InputError(f"optimiser {name!r} is not one of {', '.join(ENGINES)}")
    return ENGINES[name](low, high, n_obj, n_constr, population, seed)


# --------------------------------------------------------------------------------------- The campaign package
def open_backend(backend: str | Backend, workers: int | None, scheduler: str | None) -> tuple[Backend, bool]:
    """A backend and whether this call owns it (then it is closed by :func:`close_backend`)."""
    if isinstance(backend, Backend):
        return backend, False
    return make_backend(backend, workers, scheduler), True


def close_backend(backend: Backend, owned: bool) -> None:
    if owned:
        backend.close()


def read_table(path: str | Path) -> Results:
    return read_results(path)


def evaluate_points(
    backend: Backend,
    fn: Callable,
    spec_dict: dict,
    points: Iterable[dict],
    key: str,
    on_row: Callable[[dict], None],
    on_error: Callable[[dict, Exception], dict],
) -> None:
    """Submit ``fn(spec_dict, point)`` for every point, calling ``on_row(row)`` as each finishes
    (``on_error(point, exc)`` gives the row of a task that could not run)."""
    futures = {backend.submit(fn, spec_dict, p, key=f"qprr-design-{key}-{p['run']}"): p for p in points}
    for fut in backend.as_completed(futures):
        try:
            row = fut.result()
        except Exception as exc:  # the worker died: recorded as an error row, re-run on resume
            row = on_error(futures[fut], exc)
        on_row(row)


# -------------------------------------------------------------------------------------------- Running a study
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
    results: Results
    interrupted: bool = False


def meta_of(spec: DesignSpec) -> dict:
    return {
        "name": spec.name,
        "fingerprint": spec.fingerprint,
        "design_spec": spec.to_dict(),
        "kind": "design",
        "params": [*ID_COLUMNS[2:], *spec.parameters],
        "metrics": ["status", "reason", *DESIGN_METRICS, TAIL_COLUMNS[1]],
        "names": [],
        "n_runs": n_points(spec),
    }


def _error_row(spec: DesignSpec, p: dict, exc: Exception) -> dict:
    row = {k: p[k] for k in ID_COLUMNS}
    row.update(cells(spec, p["params"]))
    row.update(status=RunStatus.ERROR, reason=f"{type(exc).__name__}: {exc}")
    row.update(dict.fromkeys(DESIGN_METRICS, math.nan), feasible=0, wall_time=math.nan)
    return row


def told(spec: DesignSpec, rows: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """Objectives (minimisation form) and constraint violations (<= 0 feasible; the first: the design failed) of ``rows``."""
    F = np.empty((len(rows), len(spec.objectives)))
    G = np.empty((len(rows), 1 + len(spec.constraints)))
    for i, r in enumerate(rows):
        if r["status"] != RunStatus.OK:
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

    def __init__(self, spec: DesignSpec, session: Session, done: dict[int, dict]) -> None:
        self.spec, self.session, self.rows, self.bar = spec, session, done, session.bar
        self.executed, self.failed = 0, 0

    def on_row(self, row: dict) -> None:
        self.session.store.append(row)
        self.rows[int(row["run"])] = row
        self.executed += 1
        self.failed += row["status"] != RunStatus.OK
        self.bar.update(str(row["status"]))

    def evaluate(self, points: list[dict]) -> list[dict]:
        """The rows of ``points`` (evaluated now when not saved before)."""
        todo = [p for p in points if p["run"] not in self.rows or self.rows[p["run"]]["status"] == RunStatus.ERROR]
        if todo:
            be = self.session.be
            if be is None:
                be = self.session.backend()
                self.bar.message(f"{self.bar.total - self.bar.done} designs to evaluate on {be.describe()}")
            on_error = functools.partial(_error_row, self.spec)
            evaluate_points(be, evaluate_design, self.spec.to_dict(), todo, self.spec.fingerprint, self.on_row, on_error)
        return [self.rows[p["run"]] for p in points]


def _nsga2(study: _Study) -> None:
    spec = study.spec
    s = spec.search
    families = spec.families
    names = [ranged(spec, f) for f in families]
    bases = [candidates(spec, f)[0] for f in families]
    starts = block_starts(spec)
    opts = [
        make_optimiser(
            s.optimiser,
            [spec.parameters[k].low for k in names[a]],
            [spec.parameters[k].high for k in names[a]],
            len(spec.objectives),
            1 + len(spec.constraints),
            s.population,
            int(np.random.SeedSequence(spec.seed, spawn_key=(2**20, a)).generate_state(1)[0]),
        )
        if names[a]
        else None  # nothing to optimise for this family: one design
        for a in range(len(families))
    ]
    for g in range(s.generations):
        groups = []
        for a, (family, opt) in enumerate(zip(families, opts)):
            if opt is None:
                groups.append([point(spec, starts[a], "nsga2", family, bases[a], 0)] if g == 0 else [])
                continue
            first = starts[a] + g * s.population
            X = opt.ask()
            groups.append(
                [point(spec, first + k, "nsga2", family, {**bases[a], **{n: float(v) for n, v in zip(names[a], x)}}, g) for k, x in enumerate(X)]
            )
        rows = study.evaluate([p for group in groups for p in group])
        i = 0
        for opt, group in zip(opts, groups):
            if opt is not None:
                opt.tell(*told(spec, rows[i : i + len(group)]))
            i += len(group)
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
    session = Session(output, columns(spec), meta_of(spec), BackendChoice(backend, workers, scheduler), fresh)
    done: dict[int, dict] = {}
    if session.store.rows_before:
        t = read_table(session.store.path).table
        done = {int(r["run"]): {k: r[k].item() for k in t.dtype.names} for r in t}
    total = n_points(spec)
    skipped = sum(1 for r in done.values() if r["status"] != RunStatus.ERROR)
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
    return DesignRun(path, study.executed, skipped, study.failed, wall, name, read_table(path), interrupted)


def infeasible_reasons(results, spec: DesignSpec) -> list[str]:
    """Why designs of a study's table are not feasible (:func:`~qprr.design.evaluate.exclusions`), for the terminal:
    the failed evaluations' reasons and what each constraint excludes, otherwise only in the table's columns."""
    table = results.table
    return exclusions(({k: r[k].item() for k in table.dtype.names} for r in table), spec)
