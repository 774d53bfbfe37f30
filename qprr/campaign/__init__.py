"""Monte-Carlo campaigns: thousands of seeded runs, locally or on a Dask cluster, with robustness tables.

==============================  ==================================================================
module                          what
==============================  ==================================================================
:mod:`qprr.campaign.spec`       :class:`CampaignSpec` (TOML/JSON): target, grid, random draws, seeds
:mod:`qprr.campaign.metrics`    the per-run columns: RMSE (6.26), max CoG offset, saturation, ...
:mod:`qprr.campaign.worker`     the task a worker runs (model built once per worker)
:mod:`qprr.campaign.backends`   local process pool (default), Dask distributed, inline
:mod:`qprr.campaign.store`      results appended to CSV / Parquet as they arrive; resume; read
:mod:`qprr.campaign.runner`     :func:`run_campaign`: the one loop, with a progress line
:mod:`qprr.campaign.report`     summary statistics per group, box plots, heat maps, success curves
:mod:`qprr.campaign.targets`    :func:`~qprr.campaign.targets.scale_bandwidth`: one factor on a
                                loop's bandwidth (the thesis's flight as a target with its
                                mission, gains and disturbances as parameters:
                                :func:`qprr.thesis.flight.flight`)
:mod:`qprr.campaign.cli`        ``qprr campaign run SPEC`` / ``qprr campaign report RESULTS``
==============================  ==================================================================

Quick start::

    python -m qprr campaign run examples/campaigns/quickstart.toml -o quick.csv
    python -m qprr campaign report quick.csv --out quick-report

Reproducible: a specification gives the same table whatever the backend and the number of
workers (each run's draws and seed come from the specification's seed and the run index).
"""

from .backends import BACKENDS, Backend, DaskBackend, InlineBackend, LocalBackend, make_backend
from .metrics import STATUSES, metric_columns, metrics_of
from .runner import CampaignRun, run_campaign
from .spec import METRICS, MODEL_PARAMS, CampaignSpec, Distribution, Run
from .store import Results, read_results

__all__ = [
    "BACKENDS",
    "METRICS",
    "MODEL_PARAMS",
    "STATUSES",
    "Backend",
    "CampaignRun",
    "CampaignSpec",
    "DaskBackend",
    "Distribution",
    "InlineBackend",
    "LocalBackend",
    "Results",
    "Run",
    "make_backend",
    "metric_columns",
    "metrics_of",
    "read_results",
    "run_campaign",
]
