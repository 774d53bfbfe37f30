"""The one place the design search touches the campaign package (its public API only).

Backends (:func:`qprr.campaign.make_backend`: local process pool, Dask, inline), the session a
campaign runs in (:class:`qprr.campaign.session.Session`: the results store, CSV/Parquet appended as
rows arrive, fingerprint checked on resume, a lock per file; the progress line; the backend opened
at the first task and released in order), the reader (:func:`qprr.campaign.read_results`) and the flight
metrics (:func:`qprr.campaign.metrics_of`) of the closed-loop check.  If the
campaign package changes these, only this module changes.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path

from ...campaign import BACKENDS, Backend, Results, make_backend, metrics_of, read_results
from ...campaign.session import BackendChoice, Session


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


__all__ = [
    "BACKENDS",
    "Backend",
    "BackendChoice",
    "Results",
    "Session",
    "close_backend",
    "evaluate_points",
    "metrics_of",
    "open_backend",
    "read_table",
]
