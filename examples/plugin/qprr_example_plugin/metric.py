"""The plug-in's campaign metric: the largest roll or pitch of a run [rad].

A campaign metric is a :class:`qprr.campaign.CampaignMetric`: ``compute(result, names) -> float`` from a
:class:`qprr.sim.SimResult` (complete or cut by a divergence), one column named as the metric.  A specification keeps it
when its ``metrics`` names it (``metrics = ["rmse", "max_tilt"]``), and may bound it in ``[success]``.
"""

from __future__ import annotations

import math

import numpy as np

from qprr.campaign import CampaignMetric


def max_tilt(result, names) -> float:
    """max over the run of |roll| and |pitch| (xi's entries 3 and 4) [rad]; NaN for a run without a tick."""
    return float(np.max(np.abs(result.xi[:, 3:5]))) if result.n else math.nan


MAX_TILT = CampaignMetric(max_tilt, "largest roll or pitch of the run", "rad", nonnegative=True)
"""What :func:`qprr_example_plugin.register` puts in ``qprr.campaign.METRICS`` as ``max_tilt``."""
