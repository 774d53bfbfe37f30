"""Execution backends on existing engines: a local process pool (default) or Dask distributed.

Both expose the calls the campaign loop uses - :meth:`Backend.submit`, :meth:`Backend.as_completed`,
:meth:`Backend.is_lost`, :meth:`Backend.restart`, :meth:`Backend.close` and :meth:`Backend.abort` -
so a campaign has one code path:

* :class:`LocalBackend`: :class:`concurrent.futures.ProcessPoolExecutor` with the ``spawn``
  start method (no fork of a process holding Pinocchio objects), one process per core by
  default; each worker ignores SIGINT and SIGTERM (the runner stops the campaign, also when
  ``timeout`` or a job scheduler signals the whole process group) and exits at once when the
  runner aborts or dies (even by SIGKILL): it watches a pipe only the runner writes to;
* :class:`DaskBackend`: a :class:`dask.distributed.Client` on a running scheduler
  (``tcp://host:port``, the workers must have qprr installed) or on a
  :class:`dask.distributed.LocalCluster` started here, listening on the loopback interface
  only, one single-threaded worker process per core (extra ``qprr[dask]``);
* :class:`InlineBackend`: runs each task in the calling process when the loop reaches it
  (debugging, tests).

Tasks are module-level functions with plain-data arguments (:func:`qprr.campaign.worker.run_one`).
A task whose worker died, whose pool broke or whose scheduler was lost is *lost*
(:meth:`Backend.is_lost`): it produced no result, and the runner saves nothing for it.  The
runner retries lost runs on a restarted backend (:meth:`Backend.restart`: a new local pool;
Dask reschedules a dead worker's tasks by itself) while a retry round saves new rows.
"""

from __future__ import annotations

import concurrent.futures as cf
import logging
import multiprocessing
import os
import signal
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Iterator

from tqdm import tqdm

from ..errors import InputError, MissingDependencyError, UnknownNameError

BACKENDS = ("local", "dask", "inline")


def default_workers() -> int:
    """One worker per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # not on Linux
        return max(1, os.cpu_count() or 1)


def _workers(n) -> int:
    if n is None:
        return default_workers()
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise InputError(f"workers must be an integer >= 1, got {n!r}")
    return n


class Backend(ABC):
    """Where the runs execute (module docstring)."""

    name = "backend"
    workers = 1

    @abstractmethod
    def submit(self, fn: Callable, *args, key: str | None = None):
        """Schedule ``fn(*args)``; returns a future (``.result()``, ``.cancel()``)."""

    @abstractmethod
    def as_completed(self, futures: Iterable) -> Iterator:
        """The futures in the order they finish."""

    @abstractmethod
    def close(self) -> None:
        """Release the workers (pending tasks are cancelled, running ones finish)."""

    def cancel(self, futures: Iterable) -> None:
        """Cancel the tasks of ``futures`` that have not started (running ones go on)."""
        for fut in futures:
            fut.cancel()

    def abort(self, futures: Iterable = ()) -> None:
        """Stop at once (interrupt, failed write): the pending tasks of ``futures`` cancelled, running ones stopped, the
        workers released."""
        self.cancel(futures)
        self.close()

    def is_lost(self, exc: BaseException) -> bool:
        """Whether a task's exception means the run was lost with its worker or scheduler (no result), not raised by the run."""
        return False

    def restart(self) -> bool:
        """After lost tasks: make the backend usable again for a retry (True), or say it cannot (False: the runs stay lost)."""
        return False

    def describe(self) -> str:
        return f"{self.name}, {self.workers} worker{'s' if self.workers != 1 else ''}"

    def __enter__(self) -> Backend:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _watch(parent: int, stop) -> None:
    """A worker's watchdog thread: end the worker when the runner is gone (re-parented) or has closed ``stop`` (abort).

    ``stop`` is the reading end of a pipe whose only writing end the runner holds: closing it (or the runner's death)
    wakes every worker at once, and nothing waits for the workers to answer (a dead worker cannot hold the runner)."""
    while not stop.poll(0.25) and os.getppid() == parent:
        pass
    os.kill(os.getpid(), signal.SIGKILL)  # the process ends, whatever its main thread is computing


def _init_worker(parent: int, stop) -> None:
    """Initializer of a local pool's worker: Ctrl-C and SIGTERM are the runner's to handle (``timeout`` and job
    schedulers signal the whole process group); the watchdog of :func:`_watch`.

    tqdm's lock (the progress line of :func:`qprr.sim.simulate`) is a thread lock here: its default, a multiprocessing
    lock, registers a semaphore with the runner's resource tracker, which a worker stopped by its watchdog never
    unregisters, and the tracker would print a warning about it after the runner's last line."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    tqdm.set_lock(threading.RLock())
    threading.Thread(target=_watch, args=(parent, stop), name="qprr-campaign-watchdog", daemon=True).start()


class LocalBackend(Backend):
    """A pool of ``workers`` spawned processes on this machine (default: one per core); they cannot outlive the runner."""

    name = "local"

    def __init__(self, workers: int | None = None) -> None:
        self.workers = _workers(workers)
        self._pool = self._new_pool()

    def _new_pool(self) -> cf.ProcessPoolExecutor:
        ctx = multiprocessing.get_context("spawn")
        reader, self._stop = ctx.Pipe(duplex=False)  # the workers get the reading end; closing the writing end stops them
        pool = cf.ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx, initializer=_init_worker, initargs=(os.getpid(), reader))
        self._reader = reader  # kept open until the pool is replaced: a worker spawned later still gets a copy
        return pool

    def restart(self) -> bool:
        """A new pool in place of a broken one (a worker died: out of memory, killed)."""
        self.abort()  # what is left of the broken pool's workers ends with it
        self._pool = self._new_pool()
        return True

    def submit(self, fn, *args, key=None):
        return self._pool.submit(fn, *args)

    def as_completed(self, futures):
        return cf.as_completed(futures)

    def is_lost(self, exc: BaseException) -> bool:
        return isinstance(exc, (cf.process.BrokenProcessPool, cf.CancelledError))

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)
        self._close_pipe()

    def abort(self, futures: Iterable = ()) -> None:
        """The workers told to exit at once (their running tasks are dropped), the pending tasks cancelled by the pool.

        ``futures`` are not cancelled from this thread: the pool's own thread marks every pending task failed when its
        workers die, and a task cancelled here at that moment breaks that thread (Python 3.11's ProcessPoolExecutor
        raises InvalidStateError there and prints it).  Nothing here waits for an answer from a worker."""
        self._close_pipe()
        self._pool.shutdown(wait=True, cancel_futures=True)

    def _close_pipe(self) -> None:
        self._stop.close()  # every worker's watchdog reads the end of the pipe: they exit now
        self._reader.close()


class _Deferred(cf.Future):
    """A future of the inline backend: the call runs when :meth:`InlineBackend.as_completed` reaches it."""

    def __init__(self, fn: Callable, args: tuple) -> None:
        super().__init__()
        self.call = (fn, args)


class InlineBackend(Backend):
    """Runs every task in this process, one after the other, as the loop asks for it (a run saved before the next starts)."""

    name = "inline"

    def submit(self, fn, *args, key=None):
        return _Deferred(fn, args)

    def as_completed(self, futures):
        for fut in list(futures):
            if fut.set_running_or_notify_cancel():
                fn, args = fut.call
                try:
                    fut.set_result(fn(*args))
                except Exception as exc:  # the loop reports it like a failed remote task
                    fut.set_exception(exc)
            yield fut

    def close(self) -> None:
        """Nothing to release."""


def _dask():
    try:
        import distributed
    except ImportError as exc:
        raise MissingDependencyError(
            "dask.distributed", "running campaigns on Dask", "pip install 'qprr[dask]' (or pip install 'dask[distributed]')"
        ) from exc
    return distributed


class _Quiet:
    """Distributed's loggers at CRITICAL until :meth:`restore`: the runner reports lost runs itself, in one line,
    instead of the client's reconnection tracebacks."""

    def __init__(self) -> None:
        names = [
            "distributed",
            "distributed.client",
            "distributed.utils",
            "distributed.core",
            "distributed.comm",
            "distributed.batched",
            "distributed.worker",
            "distributed.nanny",
            "distributed.scheduler",
        ]
        names += [n for n in list(logging.Logger.manager.loggerDict) if n.startswith("distributed.")]
        self.levels = {n: logging.getLogger(n).level for n in dict.fromkeys(names)}
        for n in self.levels:
            logging.getLogger(n).setLevel(logging.CRITICAL)

    def restore(self) -> None:
        for n, level in self.levels.items():
            logging.getLogger(n).setLevel(level)


class DaskBackend(Backend):
    """A Dask client: on ``scheduler`` ("tcp://host:port") or on a new loopback-only LocalCluster of ``workers`` processes."""

    name = "dask"

    def __init__(self, workers: int | None = None, scheduler: str | None = None) -> None:
        distributed = _dask()
        self._cluster = None
        self._quiet = _Quiet()
        try:
            if scheduler is not None:
                if not isinstance(scheduler, str) or "://" not in scheduler:
                    raise InputError(f"scheduler must be an address such as tcp://10.0.0.5:8786, got {scheduler!r}")
                if workers is not None:
                    raise InputError("workers applies to a LocalCluster; a running scheduler has its own workers")
                try:
                    self._client = distributed.Client(scheduler, timeout="20s")
                except OSError as exc:
                    raise InputError(f"cannot reach the Dask scheduler {scheduler!r}: {exc}") from exc
                self.workers = max(1, sum(w.get("nthreads", 1) for w in self._client.scheduler_info()["workers"].values()))
                self.address = scheduler
            else:
                self.workers = _workers(workers)
                self._cluster = distributed.LocalCluster(
                    n_workers=self.workers, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None, silence_logs=logging.ERROR
                )
                self._client = distributed.Client(self._cluster)
                self.address = self._cluster.scheduler_address
        except BaseException:
            self._quiet.restore()
            raise
        self._as_completed = distributed.as_completed

    def submit(self, fn, *args, key=None):
        return self._client.submit(fn, *args, key=key, pure=False)

    def as_completed(self, futures):
        return iter(self._as_completed(list(futures)))

    def is_lost(self, exc: BaseException) -> bool:
        distributed = _dask()
        return isinstance(exc, (cf.CancelledError, distributed.KilledWorker, distributed.comm.CommClosedError, TimeoutError))

    def describe(self) -> str:
        where = "LocalCluster" if self._cluster is not None else "scheduler"
        return f"dask ({where} {self.address}), {self.workers} worker{'s' if self.workers != 1 else ''}"

    def close(self) -> None:
        try:
            self._client.close(timeout=10)  # a lost scheduler does not hold the runner
            if self._cluster is not None:
                self._cluster.close()
        finally:
            self._quiet.restore()


def make_backend(name: str = "local", workers: int | None = None, scheduler: str | None = None) -> Backend:
    """A backend by name: "local" (default), "dask" (``scheduler`` address or a LocalCluster) or "inline"."""
    if scheduler is not None and name != "dask":
        name = "dask" if name == "local" else name
        if name != "dask":
            raise InputError(f"a scheduler address needs the dask backend, not {name!r}")
    if name == "local":
        return LocalBackend(workers)
    if name == "dask":
        return DaskBackend(workers, scheduler)
    if name == "inline":
        if workers not in (None, 1):
            raise InputError(f"the inline backend runs in this process: workers must be 1, got {workers!r}")
        return InlineBackend()
    raise UnknownNameError("campaign backend", name, BACKENDS)
