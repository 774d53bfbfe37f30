"""What a campaign run and a design study share around their tasks: the results file, the progress line, the backend.

A :class:`Session` opens the results file (:class:`~qprr.campaign.store.ResultStore`: resumed
unless ``fresh``, another campaign's results refused, one writer per file), opens the backend at
the first task (:attr:`BackendChoice.backend` a name: made here with its ``workers`` / ``scheduler`` and
released here; a :class:`~qprr.campaign.backends.Backend` instance: the caller's, never closed
here), and releases them: :meth:`Session.stop` the progress line and the workers (normally, or at
once after an interruption: pending futures cancelled, running tasks stopped), :meth:`Session.close`
the file.  :func:`qprr.campaign.run_campaign` and :func:`qprr.design.run_design` both run on one.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError
from ..progress import StatusProgress
from ..validation import as_name
from .backends import BACKENDS, Backend, make_backend
from .store import ResultStore


def check_backend(backend) -> None:
    """``backend`` is a backend name (:data:`~qprr.campaign.backends.BACKENDS`) or a :class:`Backend` instance."""
    if isinstance(backend, str):
        as_name(backend, "backend", BACKENDS, kind="campaign backend")
    elif not isinstance(backend, Backend):
        raise InputError(f"backend must be one of {', '.join(BACKENDS)} or a Backend, got {type(backend).__name__}")


@dataclass(frozen=True)
class BackendChoice:
    """Where the tasks run: ``backend`` ("local" process pool, "dask" on ``scheduler`` or a LocalCluster of
    ``workers``, "inline", or a :class:`Backend` instance, which stays the caller's)."""

    backend: str | Backend = "local"
    workers: int | None = None
    scheduler: str | None = None

    def __post_init__(self) -> None:
        check_backend(self.backend)
        if self.workers is not None and (isinstance(self.workers, bool) or not isinstance(self.workers, int) or self.workers < 1):
            raise InputError(f"workers must be None (one per core) or an integer >= 1, got {self.workers!r}")
        if self.scheduler is not None and not isinstance(self.scheduler, str):
            raise InputError(f"scheduler must be None or a Dask scheduler address (a string), got {self.scheduler!r}")

    @property
    def owned(self) -> bool:
        """Whether the session makes (and so releases) the backend."""
        return not isinstance(self.backend, Backend)


class Session:
    """One run of a campaign or a design study: ``store`` (the results file), ``bar`` (set by :meth:`progress`) and
    ``be`` (the backend, None until :meth:`backend` opens it)."""

    def __init__(self, output: str | Path, columns: tuple[str, ...], meta: dict, choice: BackendChoice, fresh: bool = False) -> None:
        if not isinstance(choice, BackendChoice):
            raise InputError(f"choice must be a BackendChoice, got {type(choice).__name__}")
        check_backend(choice.backend)
        self.choice = choice
        self.be: Backend | None = None
        self.bar: StatusProgress | None = None
        self.store = ResultStore(output, columns, meta, fresh=fresh)

    def progress(self, label: str, total: int, done: int, *, quiet: bool, stream, unit: str) -> StatusProgress:
        """The progress line of the session (:class:`~qprr.progress.StatusProgress`), closed by :meth:`stop`."""
        self.bar = StatusProgress(label, total, done, quiet=quiet, stream=stream, unit=unit)
        return self.bar

    def backend(self) -> Backend:
        """The backend, opened at the first call (made from the name, or the caller's instance)."""
        if self.be is None:
            w = self.choice
            self.be = make_backend(w.backend, w.workers, w.scheduler) if w.owned else w.backend
        return self.be

    def stop(self, clean: bool = True, futures: Iterable = ()) -> None:
        """Close the progress line and release the workers: normally (``clean``) or at once (:meth:`Backend.abort`: the
        pending ``futures`` cancelled, running tasks stopped); a caller's backend is left open (only ``futures`` cancelled)."""
        if self.bar is not None:
            self.bar.close()
        if self.be is None:
            return
        if clean and self.choice.owned:
            self.be.close()
        elif self.choice.owned:
            self.be.abort(futures)
        elif not clean:
            self.be.cancel(futures)

    def close(self) -> None:
        """Close the results file (its lock released)."""
        self.store.close()


__all__ = ["BackendChoice", "Session", "check_backend"]
