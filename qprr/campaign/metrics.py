"""The numbers a campaign keeps per run, from a :class:`qprr.sim.SimResult` (complete or cut by a divergence).

=================  =========================================================================
column             meaning
=================  =========================================================================
``status``         ``ok``, ``diverged`` (NaN, runaway state, Euler singularity: the run's
                   :class:`~qprr.sim.Status`), ``failed`` (another qprr error) or ``error``
                   (any other exception: a bug, recorded rather than lost)
``reason``         why (the error message; "completed" for ``ok``)
``t_end``          simulated time reached [s] (the duration for a completed run)
``wall_time``      seconds of computation of the run
``rmse_<var>``     Thesis (6.26) per variable of xi (``SimResult.rmse``; m or rad); NaN for
                   runs that did not complete
``rmse_position``  sqrt(rmse_x^2 + rmse_y^2 + rmse_z^2): the RMSE of the position error norm [m]
``x_cm_max``       max over time of the horizontal CoG offset |(x_cm, y_cm)| in B [m]
                   (``SimResult.x_cm``: distance of the system CoM from the thrust axis z_B)
``saturation``     fraction of control ticks with a rotor thrust bound active
``recovery_time``  ``SimResult.metrics["recovery_time"]`` [s] (payload-drop: time to return
                   within tolerance after the release; inf if never); NaN when absent
``success``        1 if the run is ``ok`` and every threshold of the specification's
                   ``success`` table holds (metric <= bound), else 0
=================  =========================================================================

Runs that do not complete keep ``x_cm_max`` and ``saturation`` of their simulated part (what
led to the divergence), but no RMSE: a cut run's RMSE would mix in the runaway.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..sim import SimResult, Status
from ..validation import as_name, as_real

STATUSES = ("ok", "diverged", "failed", "error")
"""Run outcomes: the three :class:`qprr.sim.Status` values and ``error`` (an exception that is not a qprr error)."""

BASE_COLUMNS = ("status", "reason", "t_end", "wall_time")
POSITION = ("x", "y", "z")


def metric_columns(groups, names, extras=()) -> tuple[str, ...]:
    """Column names of the metric ``groups`` (see :data:`qprr.campaign.spec.METRICS`) for xi ``names``, then ``extras``."""
    from .spec import METRICS

    for arg, values in (("groups", groups), ("names", names), ("extras", extras)):
        if isinstance(values, str) or not isinstance(values, (list, tuple)) or not all(isinstance(v, str) and v for v in values):
            raise InputError(f"{arg} must be a list of names, got {values!r}")
    for g in groups:
        as_name(g, "groups", METRICS, kind="metric group")
    out = list(BASE_COLUMNS)
    for g in groups:
        if g == "rmse":
            out += [f"rmse_{n}" for n in names]
            if all(n in names for n in POSITION):
                out.append("rmse_position")
        else:
            out.append(g)
    return (*out, *extras, "success")


def metrics_of(
    result: SimResult | None, groups, names, extras=(), *, status: str | None = None, reason: str = "", wall_time: float = math.nan, success=None
) -> dict[str, object]:
    """The row of one run: :func:`metric_columns` -> value.

    ``result`` may be None (the run raised before simulating); ``status``/``reason`` override
    the result's (e.g. ``error`` with the exception text); ``success``: {metric: upper bound}.
    """
    if result is not None and not isinstance(result, SimResult):
        raise InputError(f"result must be a SimResult or None (a run that raised before simulating), got {type(result).__name__}")
    if not (isinstance(wall_time, float) and math.isnan(wall_time)):  # NaN: not measured
        wall_time = as_real(wall_time, "wall_time", nonnegative=True, unit="s")
    row: dict[str, object] = {c: math.nan for c in metric_columns(groups, names, extras)}
    row["success"] = 0
    if result is None:
        row.update(status=status or "error", reason=reason, t_end=0.0, wall_time=wall_time)
        return row
    st = status or str(result.status)
    row.update(
        status=st,
        reason=reason or result.reason,
        wall_time=result.wall_time if math.isnan(wall_time) else wall_time,
        t_end=float(result.t[-1] + result.control_period) if result.n else 0.0,
    )
    for g in groups:
        if g == "rmse":
            if st == Status.OK.value:
                e = result.rmse()
                for n in names:
                    row[f"rmse_{n}"] = e.get(n, math.nan)
                if "rmse_position" in row:
                    row["rmse_position"] = math.sqrt(sum(e[n] ** 2 for n in POSITION))
        elif g == "x_cm_max":
            row[g] = float(np.max(np.hypot(result.x_cm[:, 0], result.x_cm[:, 1]))) if result.n else math.nan
        elif g == "saturation":
            row[g] = result.saturation_fraction()
        elif g == "recovery_time":
            row[g] = float(result.metrics.get("recovery_time", math.nan))
    for k in extras:
        row[k] = float(result.metrics.get(k, math.nan))
    row["success"] = int(st == Status.OK.value and all(float(row[m]) <= bound for m, bound in (success or {}).items()))
    return row
