"""A map's sample count chosen from a time budget: pilot batches, the cost model fitted to them, the count that fits.

A map's cost grows with the configurations it evaluates (its *work*: the sizes of its joint grids, which
:func:`qprr.analysis._common.make_grid` balances over the arm's joints, so an arm with more joints gets fewer
values per joint for the same work).  How much one configuration costs depends on the platform and the machine
(the rotors, the collision model, the joint count, the load), so it is measured, never assumed:

1. **pilots**: the map is run on small grids, the requested count growing by :data:`PILOT_GROWTH` from
   :data:`PILOT_FIRST`, until one pilot takes :data:`PILOT_SHARE` of the budget and :data:`PILOT_SLOPE` times the
   one before (or the pilots took :data:`PILOT_CAP` of the budget);
2. **cost model**: t(w) = overhead + per_sample * w, the line through the last two pilots (work w, seconds t) when
   the last one took :data:`PILOT_SLOPE` times the one before; else (one pilot, times that timing noise or a fixed
   cost dominate, a negative intercept) the last pilot's t / w with no overhead, which overestimates the cost of a
   larger grid when there is an overhead: the safe side;
3. **choice**: the largest requested count whose grid work the model predicts to fit in :data:`SAFETY` times what
   the pilots left of the budget, at most :data:`MAX_SAMPLES`; when the last pilot already used it up, its result
   is the map.

The clock is a callable passed in (:func:`time.perf_counter` by default): the tests drive the choice with a fake
clock that advances by a known cost model, and never read a real one.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

from ..errors import InputError
from ..validation import as_real
from ._common import make_grid

DEFAULT_BUDGET = 10.0
"""Wall time [s] a map may take when no sample count is given (``qprr analyze --budget``; the one home of this default)."""

PILOT_FIRST = 256
"""Requested sample count of the first pilot (a grid of 3 to 4 values per joint for 4-5 joints)."""

PILOT_GROWTH = 4
"""Factor between the requested counts of successive pilots."""

PILOT_SHARE = 0.02
"""The pilots stop growing once one of them takes this share of the budget (and :data:`PILOT_SLOPE`)."""

PILOT_SLOPE = 1.5
"""... and this many times the time of the pilot before it (a quarter of its work): the per-configuration cost shows."""

PILOT_CAP = 0.3
"""The pilots stop once together they took this share of the budget, whatever they showed."""

SAFETY = 0.8
"""Share of the budget left after the pilots that the chosen map is planned to take (the model's error and the
machine's load take the rest)."""

MAX_SAMPLES = 4_000_000
"""Largest sample count a budget chooses (per region of a map): 4e6 configurations of the workspace map hold about
2 GB (points, cell zonotopes, counting grids); give ``n_samples`` for more."""


@dataclass(frozen=True)
class Pilot:
    """One pilot run: the ``requested`` sample count, the grid ``work`` it made (configurations), its ``seconds``."""

    requested: int
    work: int
    seconds: float


@dataclass(frozen=True)
class CostModel:
    """Seconds of a map against its work w (configurations): t(w) = ``overhead`` + ``per_sample`` * w."""

    overhead: float
    per_sample: float

    def seconds(self, work: int) -> float:
        """Predicted wall time [s] of a map of ``work`` configurations."""
        return self.overhead + self.per_sample * work

    @staticmethod
    def fit(pilots: tuple[Pilot, ...]) -> CostModel:
        """The line through the last two pilots when the last took :data:`PILOT_SLOPE` times the one before (its slope
        is then measured, not timing noise) and the line's overhead is >= 0; else the last pilot's t / w, no overhead
        (module docstring)."""
        last = pilots[-1]
        fallback = CostModel(0.0, last.seconds / max(last.work, 1))
        if len(pilots) < 2 or pilots[-2].work >= last.work or last.seconds < PILOT_SLOPE * pilots[-2].seconds:
            return fallback
        prev = pilots[-2]
        slope = (last.seconds - prev.seconds) / (last.work - prev.work)
        overhead = last.seconds - slope * last.work
        return CostModel(overhead, slope) if slope > 0.0 and overhead >= 0.0 else fallback


@dataclass(frozen=True)
class SampleChoice:
    """How a map's sample count was set: ``n_samples`` (requested count) and ``work`` (configurations of its grids);
    ``budget`` [s] (None: the count was given, no budget); ``pilots`` and the fitted ``model``; ``predicted`` [s] the
    model's time of the chosen map; ``note``: why the choice stopped short of the budget (a cap), or ""."""

    n_samples: int
    work: int
    budget: float | None = None
    pilots: tuple[Pilot, ...] = ()
    model: CostModel | None = None
    predicted: float | None = None
    note: str = ""

    @property
    def pilot_seconds(self) -> float:
        return float(sum(p.seconds for p in self.pilots))

    def describe(self) -> str:
        """One line for a map's summary: the count chosen and how."""
        if self.budget is None:
            return f"samples: {self.n_samples:,} given ({self.work:,} configurations); no time budget"
        pil = ", ".join(f"{p.work:,} in {p.seconds:.2g} s" for p in self.pilots)
        m = self.model
        cost = f"{m.overhead:.2g} s + {m.per_sample * 1e6:.3g} us per configuration" if m is not None else "n/a"
        line = (
            f"samples: {self.n_samples:,} requested ({self.work:,} configurations) for a budget of {self.budget:g} s: "
            f"pilots {pil} ({self.pilot_seconds:.2g} s); cost {cost}; predicted {self.predicted:.3g} s"
        )
        return line + (f"; {self.note}" if self.note else "")


def check_budget(budget) -> float | None:
    """``budget`` as seconds > 0, or None (no budget)."""
    return None if budget is None else as_real(budget, "budget", positive=True)


def check_clock(clock) -> Callable[[], float]:
    """``clock``: a callable returning seconds (None: :func:`time.perf_counter`)."""
    if clock is None:
        return time.perf_counter
    if not callable(clock):
        raise InputError(f"clock must be a callable returning seconds (e.g. time.perf_counter), got {clock!r}")
    return clock


def _pilots(run: Callable[[int], object], work: Callable[[int], int], budget: float, clock) -> tuple[tuple[Pilot, ...], object]:
    """Pilot runs of growing size (module docstring, step 1): (pilots, the last pilot's result)."""
    pilots: list[Pilot] = []
    n, result, spent = PILOT_FIRST, None, 0.0
    while True:
        t0 = clock()
        result = run(n)
        dt = max(float(clock() - t0), 0.0)
        pilots.append(Pilot(n, int(work(n)), dt))
        spent += dt
        if _enough(pilots, budget) or spent >= PILOT_CAP * budget or n >= MAX_SAMPLES:
            return tuple(pilots), result
        n = min(n * PILOT_GROWTH, MAX_SAMPLES)


def _enough(pilots: list[Pilot], budget: float) -> bool:
    """Whether the pilots can stop: two at least (the first also pays one-time costs: imports, caches), the last one
    taking :data:`PILOT_SHARE` of the budget and :data:`PILOT_SLOPE` times the one before (its time is mostly per
    configuration, not the map's fixed cost, so the line through the two has a measured slope)."""
    if len(pilots) < 2:
        return False
    last, prev = pilots[-1], pilots[-2]
    return last.seconds >= PILOT_SHARE * budget and last.seconds >= PILOT_SLOPE * prev.seconds


def _largest_within(work: Callable[[int], int], model: CostModel, seconds: float, lo: int) -> int:
    """The largest requested count in [lo, MAX_SAMPLES] whose work the model predicts within ``seconds`` (bisection:
    the work of a balanced grid never decreases with the count); ``lo`` when none is larger."""
    if model.seconds(work(MAX_SAMPLES)) <= seconds:
        return MAX_SAMPLES
    good, bad = lo, MAX_SAMPLES
    while bad - good > 1:
        mid = (good + bad) // 2
        if model.seconds(work(mid)) <= seconds:
            good = mid
        else:
            bad = mid
    return good


def choose_samples(run: Callable[[int], object], work: Callable[[int], int], budget: float, clock=None) -> tuple[SampleChoice, object]:
    """(the :class:`SampleChoice` for ``budget`` seconds, the map's result when the last pilot is the map, else None).

    ``run(n)``: the map at the requested count n (its result); ``work(n)``: the configurations its grids hold
    (no map computed); ``clock``: a callable returning seconds (default :func:`time.perf_counter`)."""
    budget = check_budget(budget)
    if budget is None:
        raise InputError("budget must be a number of seconds > 0 to choose a sample count, got None")
    clock = check_clock(clock)
    pilots, last = _pilots(run, work, budget, clock)
    model = CostModel.fit(pilots)
    left = SAFETY * (budget - sum(p.seconds for p in pilots))
    n = _largest_within(work, model, left, pilots[-1].requested)
    note = ""
    if n == MAX_SAMPLES:
        note = f"capped at {MAX_SAMPLES:,} requested samples (qprr.analysis.budget.MAX_SAMPLES: memory); give --samples for more"
    elif n == pilots[-1].requested:
        note = "the pilots used the budget: the last pilot is the map (raise --budget for finer error bars)"
    choice = SampleChoice(n, int(work(n)), budget, pilots, model, model.seconds(work(n)), note)
    return choice, (last if n == pilots[-1].requested else None)


def within_budget(options, compute: Callable, work: Callable[[int], int], progress=None):
    """The map ``compute(options, progress)`` with its ``n_samples`` chosen for ``options.budget`` (when not None)
    and its ``sampling`` set to the :class:`SampleChoice`.

    ``options``: a map's options (fields ``n_samples``, ``budget``, ``clock``); the pilots run without progress;
    ``work(n)``: the configurations of the map's grids at the requested count n."""
    if options.budget is None:
        result = compute(options, progress)
        return replace(result, sampling=SampleChoice(options.n_samples, int(work(options.n_samples))))
    fixed = replace(options, budget=None)

    def run(n: int):
        return compute(replace(fixed, n_samples=n), None)

    if progress:
        progress(0.0, f"timing pilot batches for a budget of {options.budget:g} s")
    choice, result = choose_samples(run, work, options.budget, options.clock)
    if result is None:
        result = compute(replace(fixed, n_samples=choice.n_samples), progress)
    return replace(result, sampling=choice)


def grid_work(platform, locked_sets, ranges) -> Callable[[int], int]:
    """``work(n)`` of a map over one balanced grid per locked set (:func:`qprr.analysis._common.make_grid`): the sum
    of their sizes."""
    sets = tuple(locked_sets)
    return lambda n: sum(make_grid(platform, n, lk, ranges).size for lk in sets)
