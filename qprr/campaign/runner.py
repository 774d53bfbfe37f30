"""Run a campaign: submit the runs not yet saved, save each row as it arrives, show progress.

:func:`run_campaign` is the one loop every backend goes through (:mod:`qprr.campaign.backends`).
A run's row is saved the moment it arrives (:class:`qprr.campaign.store.ResultStore`), and
its future is released then.  What stops a campaign, and what is kept:

* Ctrl-C or SIGTERM: no more runs are started, the running ones are stopped, the saved rows
  are kept; :attr:`CampaignRun.interrupted` names the signal.
* A run lost with its worker or its scheduler (:meth:`Backend.is_lost`): nothing is saved for
  it (it is not a result); it is retried on a restarted backend (:meth:`Backend.restart`) while
  a round of retries saves rows; :attr:`CampaignRun.lost` counts those left.
* A failed write (full disk, read-only folder): :class:`~qprr.campaign.store.ResultsWriteError`
  is raised after the workers are stopped; no run is started after it.

Running the same specification to the same file again resumes: only the missing runs (and the
rows of status ``error``) are submitted.
"""

from __future__ import annotations

import signal
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import InputError, UnknownNameError
from ..progress import StatusProgress
from ..validation import as_int, as_settings
from .backends import Backend
from .metrics import RunStatus, metric_columns
from .session import BackendChoice, Session, check_backend
from .spec import CampaignSpec
from .store import Results, ResultStore, check_output, read_results
from .worker import make_task_payload, nan_row, param_columns, platform_of, run_one


@dataclass
class CampaignRun:
    """What :func:`run_campaign` did.

    ``executed``: rows saved now; ``skipped``: runs already saved before; ``failed``: rows saved
    now whose status is not ``ok``; ``lost``: runs lost with their worker or scheduler (not
    saved); ``backend``: its name ("local", "dask", "inline"); ``where``: what ran the runs (e.g.
    "dask (scheduler tcp://..., 4 workers)"); ``interrupted``: "" or the signal that stopped the
    campaign ("SIGINT", "SIGTERM"); ``remaining``: runs of the specification not saved.
    """

    path: Path
    executed: int
    skipped: int
    failed: int
    wall_time: float
    backend: str
    results: Results
    interrupted: str = ""
    lost: int = 0
    where: str = ""
    remaining: int = 0

    @property
    def runs_per_second(self) -> float:
        return self.executed / self.wall_time if self.wall_time > 0 else float("nan")


def columns_of(spec: CampaignSpec, names) -> tuple[str, ...]:
    return ("run", "seed", *param_columns(spec), *metric_columns(spec.metrics, names, spec.extras))


def kinds_of(spec: CampaignSpec, names) -> dict[str, str]:
    """The kind of every column (:data:`qprr.campaign.store.KINDS`): what a row is validated against."""
    kinds = {"run": "run", "seed": "int", **{c: "text" for c in param_columns(spec)}}
    for c in metric_columns(spec.metrics, names, spec.extras):
        kinds[c] = {"status": "status", "reason": "text", "success": "flag"}.get(c, "float")
    return kinds


def check_success(spec: CampaignSpec, names) -> None:
    """Refuse ``[success]`` bounds on columns that are no metric of the campaign (the specification refuses the bounds no
    run can meet, :func:`~qprr.campaign.metrics.is_nonnegative`)."""
    if not isinstance(spec, CampaignSpec):
        raise InputError(f"spec must be a CampaignSpec, got {type(spec).__name__}")
    metrics = metric_columns(spec.metrics, names, spec.extras)
    allowed = [m for m in metrics if m not in ("status", "reason", "success")]
    for k in spec.success:
        if k not in allowed:
            raise UnknownNameError("metric of [success]", k, allowed)


class _Stop(KeyboardInterrupt):
    """SIGINT or SIGTERM, raised in the main thread while the campaign's loop runs (its argument: the signal's name)."""


class _Signals:
    """SIGINT and SIGTERM while a campaign runs (main thread only; ``timeout`` and job schedulers send SIGTERM to the
    whole process group, the workers ignore it).  The first one is noted in :attr:`fired` and, while :attr:`armed`,
    raised as :class:`_Stop`; once the workers are being released (``armed`` False) it is only noted, so that their
    release is never cut short; later signals are ignored."""

    def __init__(self) -> None:
        self.previous: dict = {}
        self.fired = ""
        self.armed = True

    def _handle(self, signum, frame) -> None:
        if not self.fired:
            self.fired = signal.Signals(signum).name
            if self.armed:
                raise _Stop(self.fired)

    def __enter__(self) -> _Signals:
        if threading.current_thread() is threading.main_thread():
            self.previous = {sig: signal.signal(sig, self._handle) for sig in (signal.SIGINT, signal.SIGTERM)}
        return self

    def __exit__(self, *exc) -> None:
        for sig, handler in self.previous.items():
            signal.signal(sig, handler)


@dataclass
class _Tally:
    skipped: int = 0
    executed: int = 0
    failed: int = 0
    lost: list = field(default_factory=list)
    lost_reason: str = ""
    interrupted: str = ""


def _collect(spec: CampaignSpec, names, be: Backend, runs: dict, store: ResultStore, bar: StatusProgress, tally: _Tally) -> None:
    """Save each row as its future completes, then release the future; lost runs are counted, not saved."""
    for fut in be.as_completed(list(runs)):
        run = runs.pop(fut)
        try:
            row = fut.result()
        except Exception as exc:
            if be.is_lost(exc):  # the worker or the scheduler went away: not a result of the run
                tally.lost.append(run)
                tally.lost_reason = tally.lost_reason or f"{type(exc).__name__}: {exc}".strip().splitlines()[0]
                continue
            row = nan_row(spec, names, run, RunStatus.ERROR, f"{type(exc).__name__}: {exc}")  # the task could not run
        store.append(row)
        tally.executed += 1
        tally.failed += row["status"] != RunStatus.OK
        bar.update(str(row["status"]))


@dataclass(frozen=True)
class CampaignRunOptions:
    """How :func:`run_campaign` runs a campaign: ``backend`` "local" (process pool, default), "dask" (``scheduler``
    address or a LocalCluster of ``workers``), "inline", or a :class:`Backend` instance (not closed by the run);
    ``fresh``: discard existing results; ``limit``: run at most this many of the missing runs (the first ones by
    index); ``progress``: the progress line (on ``stream``, default stderr)."""

    backend: str | Backend = "local"
    workers: int | None = None
    scheduler: str | None = None
    fresh: bool = False
    limit: int | None = None
    progress: bool = True
    stream: object = None

    def __post_init__(self) -> None:  # checked however the options are built
        BackendChoice(self.backend, self.workers, self.scheduler)
        if self.limit is not None:
            object.__setattr__(self, "limit", as_int(self.limit, "limit", lo=0))


def run_campaign(spec: CampaignSpec, output: str | Path, options: CampaignRunOptions | None = None, **settings) -> CampaignRun:
    """Run ``spec``, saving rows to ``output`` (.csv or .parquet) as they arrive; resume what is there.

    ``options``: a :class:`CampaignRunOptions`, and/or its fields as keywords, which replace the options'
    (``run_campaign(spec, "out.csv", backend="inline", progress=False)``).  Returns a :class:`CampaignRun`; raises
    :class:`~qprr.campaign.store.ResultsWriteError` when a row cannot be written (the workers
    stopped first, the rows saved before kept) and :class:`~qprr.campaign.store.ResultsFileError`
    when the existing results hold a bad row.
    """
    o = as_settings(options, CampaignRunOptions, "options", **settings)
    backend, limit, progress = o.backend, o.limit, o.progress
    if not isinstance(spec, CampaignSpec):
        raise InputError(f"spec must be a CampaignSpec, got {type(spec).__name__}")
    if limit is not None:
        limit = as_int(limit, "limit", lo=0)
    output = check_output(output, "output")  # before any run
    check_backend(backend)
    platform = platform_of(spec)
    names = platform.xi_names
    check_success(spec, names)
    meta = _meta(spec, platform)
    payload = make_task_payload(spec)  # reads a user file now: a missing one fails before any worker starts
    session = Session(output, columns_of(spec, names), meta, BackendChoice(backend, o.workers, o.scheduler), o.fresh)
    store = session.store
    todo = [i for i in range(spec.n_runs) if i not in store.done]
    if limit is not None:
        todo = todo[:limit]
    t0 = time.perf_counter()
    tally, runs, clean = _Tally(skipped=len(store.done)), {}, False
    bar = session.progress(f"campaign {spec.name}", tally.skipped + len(todo), tally.skipped, quiet=not progress, stream=o.stream, unit="run")
    if store.dropped:  # shown even without the progress line (--quiet): a cut write is never repaired silently
        print(
            f"campaign {spec.name}: dropped an incomplete last record ({store.dropped} bytes, a cut write) of {store.path}: its run is done again",
            file=bar.stream,
        )
    try:
        with _Signals() as signals:
            try:
                try:
                    if todo:
                        _run_missing(spec, names, session, payload, todo, runs, tally, progress)
                    clean = True
                finally:
                    signals.armed = False  # from here on a signal is noted, not raised: the workers' release runs to its end
            except KeyboardInterrupt:  # _Stop, or Ctrl-C where no handler could be set (not the main thread)
                signals.fired = signals.fired or "SIGINT"
            finally:
                session.stop(clean and not signals.fired, runs)
            tally.interrupted = signals.fired
    finally:
        session.close()
    return _finish(spec, store, session.be, backend, tally, time.perf_counter() - t0, bar.stream if progress else None)


def _meta(spec: CampaignSpec, platform) -> dict:
    """What the results' ``.meta.json`` keeps beside the table: the specification, the columns' roles and kinds, the
    platform's model name and its arm joints' types (the units of their columns)."""
    names = platform.xi_names
    return {
        "name": spec.name,
        "fingerprint": spec.fingerprint,
        "spec": spec.to_dict(),
        "params": list(param_columns(spec)),
        "metrics": list(metric_columns(spec.metrics, names, spec.extras)),
        "names": list(names),
        "platform": platform.name,
        "arm_kinds": [j.kind for j in platform.arm],
        "n_runs": spec.n_runs,
        "kinds": kinds_of(spec, names),
    }


def _run_missing(spec: CampaignSpec, names, session: Session, payload, todo: list[int], runs: dict, tally: _Tally, progress: bool) -> None:
    """Submit the runs ``todo`` and save their rows; runs lost with their worker are retried on a restarted backend while
    a round of retries saves rows."""
    be, store, bar = session.backend(), session.store, session.bar
    if progress:
        print(f"campaign {spec.name}: {len(todo)} runs to do ({tally.skipped} already in {store.path}) on {be.describe()}", file=bar.stream)
    pending = [spec.run(i) for i in todo]
    while pending:
        saved_before = tally.executed
        runs.update({be.submit(run_one, payload, r, key=f"qprr-{spec.fingerprint}-{r.index}"): r for r in pending})
        _collect(spec, names, be, runs, store, bar, tally)
        retry = bool(tally.lost) and tally.executed > saved_before and be.restart()
        pending, tally.lost = (tally.lost, []) if retry else ([], tally.lost)


def _finish(spec, store, be, backend, tally: _Tally, wall: float, stream) -> CampaignRun:
    """The table read back, the messages of an interrupted or lossy campaign (on ``stream``, if any), the record."""
    results = read_results(store.path)
    saved = len({int(r) for r in results.table["run"]})
    remaining = spec.n_runs - saved
    if stream is not None and tally.interrupted:
        print(
            f"campaign {spec.name}: stopped by {tally.interrupted} after {tally.executed} runs; {saved}/{spec.n_runs} saved in "
            f"{store.path}; run the same command again to resume",
            file=stream,
        )
    if stream is not None and tally.lost:
        print(
            f"campaign {spec.name}: {len(tally.lost)} runs lost with their worker or scheduler ({tally.lost_reason}), not saved; "
            f"run the same command again to run them",
            file=stream,
        )
    name = be.name if be is not None else backend if isinstance(backend, str) else backend.name
    return CampaignRun(
        store.path,
        tally.executed,
        tally.skipped,
        tally.failed,
        wall,
        name,
        results,
        tally.interrupted,
        len(tally.lost),
        be.describe() if be is not None else "nothing to run",
        remaining,
    )


__all__ = ["CampaignRun", "check_success", "run_campaign"]
