"""Monte-Carlo campaigns: thousands of seeded runs, locally or on a Dask cluster, with robustness tables.

==============================  ==================================================================
module                          what
==============================  ==================================================================
:mod:`qprr.campaign.spec`       :class:`CampaignSpec` (TOML/JSON): target, grid, random draws, seeds
:mod:`qprr.campaign.metrics`    the per-run columns: RMSE (6.26), max CoG offset, saturation, ...; the
                                registry :data:`METRICS` plug-ins add their metrics to
:mod:`qprr.campaign.worker`     the task a worker runs (model built once per worker)
:mod:`qprr.campaign.backends`   local process pool (default), Dask distributed, inline
:mod:`qprr.campaign.store`      results appended as they arrive (one checksummed CSV record per
                                line, or Parquet parts); resume after a cut; validated reads
:mod:`qprr.campaign.session`    :class:`~qprr.campaign.session.Session`: results store, progress
                                line and backend of one run (shared with :mod:`qprr.design`)
:mod:`qprr.campaign.runner`     :func:`run_campaign`: the one loop, with a progress line
:mod:`qprr.campaign.report`     summary statistics per group, box plots, heat maps, success
                                curves; the platform named in the header and titles
:mod:`qprr.campaign.targets`    :func:`~qprr.campaign.targets.scale_bandwidth`: one factor on a
                                loop's bandwidth (the thesis's flight as a target with its
                                mission, gains and disturbances as parameters:
                                :func:`qprr.thesis.flight.flight`)
:mod:`qprr.campaign.cli`        ``qprr campaign run SPEC`` / ``qprr campaign report RESULTS``
==============================  ==================================================================

Quick start::

    python -m qprr campaign run examples/campaigns/quickstart.toml -o quick.csv
    python -m qprr campaign report quick.csv --out quick-report

Any platform: ``platform = "borinot_flying_arm_2"`` (any registered name or a (2.1) designation)
or ``platform = {urdf = "robot.urdf", rotors = "robot.rotors.toml", ee_frame = "gripper"}`` (paths
relative to the specification; the files' content is part of its fingerprint); the ``rmse_*``
columns carry the platform's coordinate names.

Reproducible: a specification gives the same table whatever the backend and the number of
workers (each run's draws and seed come from the specification's seed and the run index).

Public API for other packages (e.g. a design search that runs its evaluations here):

* ``run_campaign(spec, output, options=None, **settings) -> CampaignRun``: the one loop; ``options`` a
  :class:`CampaignRunOptions` (backend="local", workers=None, scheduler=None, fresh=False, limit=None,
  progress=True, stream=None), its fields also keywords.  ``CampaignRun``:
  ``path``, ``executed``, ``skipped``, ``failed``, ``lost`` (runs lost with a worker or the
  scheduler: not saved), ``interrupted`` ("" or "SIGINT"/"SIGTERM"), ``remaining`` (runs of the
  specification not saved), ``backend`` (name), ``where`` (what ran them), ``wall_time``,
  ``results``.  Raises :class:`~qprr.campaign.store.ResultsWriteError` (a failed write: the
  workers are stopped first) and :class:`~qprr.campaign.store.ResultsFileError` (a bad row in
  the file it resumes).
* ``make_backend(name, workers, scheduler) -> Backend``: ``submit(fn, *args, key=None)`` ->
  future, ``as_completed(futures)``, ``is_lost(exc)`` (the future's exception means its worker
  or scheduler went away), ``restart()`` (usable again after lost tasks: True for a new local
  pool), ``close()``, ``abort()`` (stop at once).  Tasks: module-level
  functions with plain-data arguments.
* ``ResultStore(path, columns, meta, *, fresh=False)``: ``append(row)``, ``flush()``,
  ``close()``, ``done`` (run indices saved, status not ``error``), ``dropped`` (bytes of a cut
  record removed on resume).  ``meta`` needs ``fingerprint``; optional ``kinds`` (column ->
  :data:`~qprr.campaign.store.KINDS`), ``n_runs`` and ``spec`` validate the rows.  ``columns``
  must include ``run``.  ``read_results(path) -> Results`` (validated; ``table``, a numpy
  structured array sorted by run), ``read_meta(path)``.
* ``Session(output, columns, meta, BackendChoice(backend, workers, scheduler), fresh)``
  (:mod:`qprr.campaign.session`): the store, ``progress(...)`` (the progress line),
  ``backend()`` (opened at the first call), ``stop(clean, futures)`` (progress line and
  workers released), ``close()`` (the file).
"""

from .backends import BACKENDS, Backend, DaskBackend, InlineBackend, LocalBackend, make_backend
from .metrics import DEFAULT_METRICS, METRICS, STATUSES, CampaignMetric, metric_columns, metrics_of
from .runner import CampaignRun, CampaignRunOptions, run_campaign
from .spec import MODEL_PARAMS, CampaignSpec, Distribution, Run
from .store import KINDS, Results, ResultsFileError, ResultStore, ResultsWriteError, read_meta, read_results

__all__ = [
    "BACKENDS",
    "DEFAULT_METRICS",
    "KINDS",
    "METRICS",
    "MODEL_PARAMS",
    "STATUSES",
    "Backend",
    "CampaignMetric",
    "CampaignRun",
    "CampaignRunOptions",
    "CampaignSpec",
    "DaskBackend",
    "Distribution",
    "InlineBackend",
    "LocalBackend",
    "ResultStore",
    "Results",
    "ResultsFileError",
    "ResultsWriteError",
    "Run",
    "make_backend",
    "metric_columns",
    "metrics_of",
    "read_meta",
    "read_results",
    "run_campaign",
]
