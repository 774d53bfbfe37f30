"""Many inverse-kinematics targets in one call: :func:`solve_many` and its result :class:`IKBatch`.

    batch = solve_many(IKSolver(platform), targets, workers=2)   # targets: positions, (p, R) pairs or SE3
    print(batch.summary()); batch.success                         # (n,) bool, in the targets' order

Every target is solved by :meth:`qprr.ik.IKSolver.solve` from its own start (``xi0``: none, one for all, or one per
target), so the answers are those of the same solves made one by one, whatever ``workers``: the batch only spreads
the targets over processes (``workers`` > 1: contiguous chunks, each process building the same solver from its
constructor's arguments once per chunk -- a solver's compiled kernels are not sent, they load from numba's cache --)
and gathers the results in order.  It pays off from a few hundred targets (a process costs about a second to start
here); on one core ``workers=1`` solves in this process with one :class:`pinocchio.Data`.
"""

from __future__ import annotations

import pickle
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..kinematics import ee_pose_xi
from ..model import Platform
from ..validation import as_int
from .solver import IKOutcome, IKResult, IKSolver, parse_target

CHUNKS_PER_WORKER = 4
"""Chunks each worker process gets on average (``workers`` > 1): more chunks balance uneven solve times, fewer save
the solver's unpickling."""


def reachable_targets(platform: Platform, n: int, seed: int = 0) -> list[np.ndarray]:
    """``n`` end-effector positions p_world [m] reachable by construction: those of random hover configurations (base
    within 1 m of (0, 0, 2) m, any yaw, arm joints uniform within their limits clipped to +-3), seeded by ``seed``."""
    n = as_int(n, "n", lo=0)
    rng = np.random.default_rng(seed)
    data = platform.data()
    out = []
    for _ in range(n):
        xi = platform.neutral_xi().copy()
        xi[0:3] = rng.uniform(-1.0, 1.0, 3) + (0.0, 0.0, 2.0)
        xi[5] = rng.uniform(-np.pi, np.pi)
        xi[6:] = rng.uniform(np.maximum(platform.arm_lower, -3.0), np.minimum(platform.arm_upper, 3.0))
        out.append(ee_pose_xi(platform, data, xi)[0])
    return out


@dataclass(frozen=True)
class IKBatch:
    """Results of :func:`solve_many`, one :class:`~qprr.ik.IKResult` per target in the targets' order.

    ``platform_name``, ``method``: what solved them; ``xi_names``: the names of the coordinates of ``xi`` (thesis
    coordinates, the platform's arm joint names).
    """

    platform_name: str
    method: str
    xi_names: tuple[str, ...]
    results: tuple[IKResult, ...]

    def __len__(self) -> int:
        return len(self.results)

    def __iter__(self):
        return iter(self.results)

    def __getitem__(self, k: int) -> IKResult:
        return self.results[k]

    @property
    def success(self) -> np.ndarray:
        """(n,) bool: each target reached (pose, limits and, where required, hover)."""
        return np.array([r.success for r in self.results], dtype=bool)

    @property
    def status(self) -> tuple[IKOutcome, ...]:
        return tuple(r.status for r in self.results)

    @property
    def xi(self) -> np.ndarray:
        """(n, 6 + n_arm) returned configurations (thesis coordinates; NaN where a method returned none)."""
        nan = np.full(len(self.xi_names), np.nan)
        return np.array([nan if r.xi is None else r.xi for r in self.results])

    @property
    def position_error(self) -> np.ndarray:
        """(n,) world position error [m] of each returned configuration."""
        return np.array([r.position_error for r in self.results])

    @property
    def orientation_error(self) -> np.ndarray:
        """(n,) rotation angle error [rad] (0 for a position target)."""
        return np.array([r.orientation_error for r in self.results])

    @property
    def iterations(self) -> np.ndarray:
        return np.array([r.iterations for r in self.results], dtype=np.int64)

    def counts(self) -> dict[str, int]:
        """How many targets ended with each status (the statuses that occurred, by name)."""
        out: dict[str, int] = {}
        for s in self.status:
            out[s.value] = out.get(s.value, 0) + 1
        return out

    def summary(self, failures: int = 10) -> str:
        """Reached count, statuses, iterations, the worst errors of the reached targets, and the first ``failures``
        targets not reached with their reasons."""
        n, ok = len(self), int(self.success.sum())
        lines = [f"ik on {self.platform_name}, method {self.method}: {ok} of {n} targets reached"]
        lines.append("  statuses: " + ", ".join(f"{k} {v}" for k, v in self.counts().items()))
        if n:
            lines.append(f"  iterations: median {np.median(self.iterations):.3g}, largest {int(self.iterations.max())}")
        if ok:
            pe, oe = self.position_error[self.success], self.orientation_error[self.success]
            lines.append(f"  reached: largest position error {pe.max():.3g} m, orientation error {oe.max():.3g} rad")
        missed = [k for k, r in enumerate(self.results) if not r.success]
        for k in missed[:failures]:
            lines.append(f"  target {k}: {self.results[k].status.value}: {self.results[k].reason}")
        if len(missed) > failures:
            lines.append(f"  ... and {len(missed) - failures} more not reached")
        return "\n".join(lines)

    def rows(self) -> list[dict[str, object]]:
        """One row per target for a table (CSV): index, success, status, errors [m, rad], iterations, then xi by name."""
        rows = []
        for k, (r, xi) in enumerate(zip(self.results, self.xi)):
            row: dict[str, object] = {"target": k, "success": r.success, "status": r.status.value}
            row |= {"position_error": r.position_error, "orientation_error": r.orientation_error, "iterations": r.iterations}
            row |= dict(zip(self.xi_names, xi.tolist()))
            rows.append(row)
        return rows


def _starts(xi0, n: int, n_xi: int) -> list:
    """``xi0`` as one start per target: None (each target's initial guess), one (6 + n_arm,) for all, an (n, 6 + n_arm)
    array, or a sequence of n entries each None or (6 + n_arm,)."""
    if xi0 is None:
        return [None] * n
    if isinstance(xi0, (list, tuple)) and all(isinstance(x, (int, float)) for x in xi0) and len(xi0) == n_xi:
        return [np.asarray(xi0, dtype=float)] * n  # one start for all, written as a list of numbers
    if isinstance(xi0, (list, tuple)):
        if len(xi0) != n:
            raise InputError(f"xi0 must have one entry per target ({n}), got {len(xi0)}")
        return [None if x is None else _start(x, n_xi, f"xi0[{k}]") for k, x in enumerate(xi0)]
    a = np.asarray(xi0, dtype=float)
    if a.shape == (n_xi,):
        return [a] * n
    if a.shape == (n, n_xi):
        return list(a)
    raise InputError(f"xi0 must be None, one start of {n_xi} thesis coordinates or one per target ({n}, {n_xi}); got shape {a.shape}")


def _start(x, n_xi: int, what: str) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.shape != (n_xi,):
        raise InputError(f"{what} must be a start of {n_xi} thesis coordinates, got shape {a.shape}")
    return a


@dataclass(frozen=True)
class _SolverRecipe:
    """What builds an :class:`~qprr.ik.IKSolver` (its constructor's arguments), sent to the worker processes."""

    platform: Platform
    method: str
    options: object
    initial_guess: object
    unreachable_hint: object

    @classmethod
    def of(cls, solver: IKSolver) -> _SolverRecipe:
        return cls(solver.platform, solver.method, solver.options, solver.initial_guess, solver.unreachable_hint)

    def build(self) -> IKSolver:
        return IKSolver(self.platform, self.method, self.options, initial_guess=self.initial_guess, unreachable_hint=self.unreachable_hint)


def _solve_chunk(solver: IKSolver, targets: list, starts: list) -> list[IKResult]:
    """Solve ``targets`` one by one from ``starts`` with one pinocchio Data."""
    data = solver.platform.model.createData()
    return [solver.solve(data, target, xi0) for target, xi0 in zip(targets, starts)]


def _solve_chunk_in_worker(recipe: _SolverRecipe, targets: list, starts: list) -> list[IKResult]:
    """:func:`_solve_chunk` in a worker process, with the solver ``recipe`` builds."""
    return _solve_chunk(recipe.build(), targets, starts)


def solve_many(solver: IKSolver, targets: Sequence, *, xi0=None, workers: int = 1, progress: Callable[[float, str], None] | None = None) -> IKBatch:
    """Solve every target of ``targets`` with ``solver`` (module docstring): the answers of one ``solver.solve`` per
    target, in order (every solve starts afresh; the targets are not run in lockstep: their iterations branch
    differently -- active joint limits, frozen levels, restarts).  ``xi0``: None, one start for all, or one per target
    (thesis coordinates; entries None: the initial guess); ``workers``: processes (1: this one); ``progress``: a
    callable (fraction, message).  A bad target or start raises before any target is solved."""
    if not isinstance(solver, IKSolver):
        raise InputError(f"solver must be a qprr.ik.IKSolver (IKSolver(platform, method)), got {type(solver).__name__}")
    if isinstance(targets, np.ndarray) and targets.ndim == 2:
        targets = list(targets)
    if not isinstance(targets, Sequence) or isinstance(targets, (str, bytes)):
        raise InputError(f"targets must be a sequence of targets (positions [m], (p, R) pairs or SE3), got {type(targets).__name__}")
    for k, target in enumerate(targets):
        try:
            parse_target(target)
        except InputError as exc:
            raise exc.within(f"targets[{k}]") from None
    workers = as_int(workers, "workers", lo=1)
    platform = solver.platform
    starts = _starts(xi0, len(targets), len(platform.xi_names))
    results: list[IKResult] = []
    if workers == 1 or len(targets) < 2:
        step = max(1, len(targets) // 100)
        for lo in range(0, len(targets), step):
            results += _solve_chunk(solver, list(targets[lo : lo + step]), starts[lo : lo + step])
            if progress:
                progress(len(results) / len(targets), f"ik on {platform.name}")
    else:
        results = _in_processes(solver, list(targets), starts, workers, progress)
    return IKBatch(platform.name, solver.method, tuple(platform.xi_names), tuple(results))


def _in_processes(solver: IKSolver, targets: list, starts: list, workers: int, progress) -> list[IKResult]:
    """The targets in contiguous chunks over ``workers`` processes, the results gathered in the targets' order."""
    recipe = _SolverRecipe.of(solver)
    try:
        pickle.dumps(recipe)
    except (pickle.PicklingError, AttributeError, TypeError) as exc:
        raise InputError(
            f"workers = {workers}: the solver cannot be sent to worker processes ({exc}); its initial_guess and "
            "unreachable_hint must be module-level functions (not lambdas or local functions), or use workers = 1"
        ) from None
    n_chunks = min(len(targets), workers * CHUNKS_PER_WORKER)
    bounds = np.linspace(0, len(targets), n_chunks + 1).astype(int)
    by_start: dict[int, list[IKResult]] = {}
    done = 0
    with ProcessPoolExecutor(max_workers=workers) as pool:
        futures = {pool.submit(_solve_chunk_in_worker, recipe, targets[lo:hi], starts[lo:hi]): lo for lo, hi in zip(bounds[:-1], bounds[1:])}
        for future in as_completed(futures):
            if future.exception() is not None:  # a worker failed: the chunks not started are dropped, then it is raised
                pool.shutdown(wait=False, cancel_futures=True)
            chunk = future.result()
            by_start[futures[future]] = chunk
            done += len(chunk)
            if progress:
                progress(done / len(targets), f"ik on {solver.platform.name}")
    return [r for lo in sorted(by_start) for r in by_start[lo]]


__all__ = ["CHUNKS_PER_WORKER", "IKBatch", "solve_many"]
