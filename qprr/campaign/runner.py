"""Run a campaign: submit the runs not yet saved, save each row as it arrives, show progress.

:func:`run_campaign` is the one loop every backend goes through (:mod:`qprr.campaign.backends`).
A run's row is saved the moment it arrives (:class:`qprr.campaign.store.ResultStore`);
interrupting (Ctrl-C) cancels the pending runs and keeps the saved ones; running the same
specification to the same file again resumes: only the missing runs (and the rows of status
``error``, a worker that died) are submitted.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path

from ..charts import as_int, as_name
from ..errors import InputError, UnknownNameError
from .backends import BACKENDS, Backend, make_backend
from .metrics import metric_columns
from .spec import CampaignSpec
from .store import Results, ResultStore, check_output, read_results
from .worker import make_payload, nan_row, param_columns, run_one, xi_names_of


def _duration(s: float) -> str:
    if s != s or s == float("inf"):
        return "--"
    s = int(round(s))
    h, r = divmod(s, 3600)
    m, sec = divmod(r, 60)
    return f"{h}h{m:02d}m{sec:02d}s" if h else f"{m}m{sec:02d}s" if m else f"{sec}s"


class Progress:
    """One status line on stderr: runs done / total, failed, rate and ETA.

    On a terminal the line is rewritten in place; otherwise a line is printed every 10 % of the
    runs or every 30 s, whichever comes first.
    """

    def __init__(self, name: str, total: int, done: int = 0, enabled: bool = True, stream=None) -> None:
        self.name, self.total, self.start_done = name, total, done
        self.done, self.failed = done, 0
        self.enabled = enabled
        self.stream = sys.stderr if stream is None else stream
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.t0 = time.perf_counter()
        self._last_print, self._last_frac = self.t0, done / total if total else 1.0

    def line(self) -> str:
        el = time.perf_counter() - self.t0
        new = self.done - self.start_done
        rate = new / el if el > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("nan")
        return (f"campaign {self.name}: {self.done}/{self.total} runs, {self.failed} failed, "
                f"{rate:.2f} runs/s, elapsed {_duration(el)}, ETA {_duration(eta)}")

    def update(self, status: str) -> None:
        self.done += 1
        if status != "ok":
            self.failed += 1
        if not self.enabled:
            return
        now = time.perf_counter()
        if self.tty:
            self.stream.write("\r" + self.line() + "\033[K")
            self.stream.flush()
        elif self.done == self.total or now - self._last_print > 30.0 or self.done / self.total - self._last_frac >= 0.1:
            self.stream.write(self.line() + "\n")
            self.stream.flush()
            self._last_print, self._last_frac = now, self.done / self.total

    def close(self) -> None:
        if self.enabled and self.tty:
            self.stream.write("\n")
            self.stream.flush()


@dataclass
class CampaignRun:
    """What :func:`run_campaign` did: the results file, the runs executed now, failures, wall time, the table."""

    path: Path
    executed: int
    skipped: int
    failed: int
    wall_time: float
    backend: str
    results: Results
    interrupted: bool = False

    @property
    def runs_per_second(self) -> float:
        return self.executed / self.wall_time if self.wall_time > 0 else float("nan")


def columns_of(spec: CampaignSpec, names) -> tuple[str, ...]:
    return ("run", "seed", *param_columns(spec), *metric_columns(spec.metrics, names, spec.extras))


def run_campaign(spec: CampaignSpec, output: str | Path, *, backend: str | Backend = "local", workers: int | None = None,
                 scheduler: str | None = None, fresh: bool = False, limit: int | None = None, progress: bool = True,
                 stream=None) -> CampaignRun:
    """Run ``spec``, saving rows to ``output`` (.csv or .parquet) as they arrive; resume what is there.

    ``backend``: "local" (process pool, default), "dask" (``scheduler`` address or a
    LocalCluster of ``workers``), "inline", or a :class:`Backend` instance (not closed here).
    ``fresh``: discard existing results.  ``limit``: run at most this many of the missing runs
    (the first ones by index).  Returns a :class:`CampaignRun`.
    """
    if not isinstance(spec, CampaignSpec):
        raise InputError(f"spec must be a CampaignSpec, got {type(spec).__name__}")
    if limit is not None:
        limit = as_int(limit, "limit", lo=0)
    output = check_output(output, "output")  # before any run
    if isinstance(backend, str):
        as_name(backend, "backend", BACKENDS, kind="campaign backend")
    elif not isinstance(backend, Backend):
        raise InputError(f"backend must be one of {', '.join(BACKENDS)} or a Backend, got {type(backend).__name__}")
    names = xi_names_of(spec)
    columns = columns_of(spec, names)
    for k in spec.success:
        if k not in columns or k in ("status", "reason", "success"):
            raise UnknownNameError("metric of [success]", k, metric_columns(spec.metrics, names, spec.extras)[2:-1])
    meta = {"name": spec.name, "fingerprint": spec.fingerprint, "spec": spec.to_dict(), "params": list(param_columns(spec)),
            "metrics": list(metric_columns(spec.metrics, names, spec.extras)), "names": list(names), "n_runs": spec.n_runs}
    payload = make_payload(spec)  # reads a user file now: a missing one fails before any worker starts
    store = ResultStore(output, columns, meta, fresh=fresh)
    todo = [i for i in range(spec.n_runs) if i not in store.done]
    if limit is not None:
        todo = todo[:limit]
    skipped = len(store.done)
    own = not isinstance(backend, Backend)
    t0 = time.perf_counter()
    bar = Progress(spec.name, skipped + len(todo), skipped, enabled=progress, stream=stream)
    executed = failed = 0
    interrupted = False
    be = None
    try:
        if todo:
            be = make_backend(backend, workers, scheduler) if own else backend
            if progress:
                print(f"campaign {spec.name}: {len(todo)} runs to do ({skipped} already in {store.path}) on {be.describe()}",
                      file=bar.stream)
            runs = {}
            for i in todo:
                run = spec.run(i)
                runs[be.submit(run_one, payload, run, key=f"qprr-{spec.fingerprint}-{i}")] = run
            for fut in be.as_completed(runs):
                run = runs[fut]
                try:
                    row = fut.result()
                except Exception as exc:  # the worker died or the task could not run: recorded, re-run on resume
                    row = nan_row(spec, names, run, "error", f"{type(exc).__name__}: {exc}")
                store.append(row)
                executed += 1
                failed += row["status"] != "ok"
                bar.update(str(row["status"]))
    except KeyboardInterrupt:
        interrupted = True
    finally:
        store.close()
        bar.close()
        if be is not None and own:
            be.close()
    wall = time.perf_counter() - t0
    if interrupted and progress:
        print(f"campaign {spec.name}: interrupted after {executed} runs; run the same command again to resume", file=bar.stream)
    return CampaignRun(store.path, executed, skipped, failed, wall, backend if isinstance(backend, str) else backend.name,
                       read_results(store.path), interrupted)


__all__ = ["CampaignRun", "run_campaign"]
