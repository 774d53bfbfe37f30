"""The numbers a campaign keeps per run, from a :class:`qprr.sim.SimResult` (complete or cut by a divergence).

The metric groups are the registry :data:`METRICS` (``rmse``, ``x_cm_max``, ``saturation``, ``recovery_time``, then the
plug-ins' :class:`CampaignMetric` entries, docs/extending.md); a specification keeps :data:`DEFAULT_METRICS` unless
its ``metrics`` names others.

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
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum

import numpy as np

from ..errors import InputError, UnknownNameError
from ..registry import Registry
from ..sim import SimResult
from ..validation import as_name, as_real


class RunStatus(str, Enum):
    """How a run of a campaign ended (the ``status`` column): the three :class:`qprr.sim.Status` values and ``error``
    (an exception that is not a qprr error: a bug, recorded rather than lost).  A ``str``: the table's text compares
    equal (``table["status"] == RunStatus.OK``)."""

    OK = "ok"
    DIVERGED = "diverged"
    FAILED = "failed"
    ERROR = "error"

    def __str__(self) -> str:
        return self.value


STATUSES = tuple(s.value for s in RunStatus)
"""The texts of the ``status`` column (:class:`RunStatus` values)."""


def run_status(status) -> RunStatus:
    """``status`` (a :class:`RunStatus`, a :class:`qprr.sim.Status` or the text of either) as a :class:`RunStatus`."""
    if isinstance(status, str) and status in STATUSES:
        return RunStatus(str(status))
    raise UnknownNameError("run status", status, STATUSES)


BASE_COLUMNS = ("status", "reason", "t_end", "wall_time")
POSITION = ("x", "y", "z")


@dataclass(frozen=True)
class CampaignMetric:
    """A metric a campaign may keep per run (a name of ``metrics`` in a specification).

    ``compute(result, names)``: the value from a :class:`qprr.sim.SimResult` (complete or cut by a divergence) and
    the platform's coordinate names ``names`` (xi's): a number for a one-column metric (its column is the metric's
    name), or ``{column: value}`` when ``columns(names)`` gives the metric's columns (``rmse``: one per coordinate).
    ``complete_only``: NaN for a run that did not complete (a cut run's RMSE would mix in the runaway);
    ``nonnegative``: every value is >= 0 (a negative ``[success]`` bound on it is refused: no run could meet it);
    ``unit`` of the column(s) in the report's labels; ``description``: one line."""

    compute: Callable[[SimResult, tuple[str, ...]], object]
    description: str = ""
    unit: str = ""
    columns: Callable[[tuple[str, ...]], tuple[str, ...]] | None = None
    complete_only: bool = False
    nonnegative: bool = False

    def __post_init__(self) -> None:
        if not callable(self.compute):
            raise InputError(f"CampaignMetric.compute must be a function (result, names) -> value, got {self.compute!r}")
        if self.columns is not None and not callable(self.columns):
            raise InputError(f"CampaignMetric.columns must be None or a function (names) -> column names, got {self.columns!r}")
        for flag in ("complete_only", "nonnegative"):
            if not isinstance(getattr(self, flag), bool):
                raise InputError(f"CampaignMetric.{flag} must be True or False, got {getattr(self, flag)!r}")

    def column_names(self, name: str, names: tuple[str, ...]) -> tuple[str, ...]:
        """The columns of the metric registered as ``name`` for xi's ``names``."""
        return (name,) if self.columns is None else tuple(self.columns(names))

    def values(self, name: str, result: SimResult, names: tuple[str, ...], complete: bool) -> dict[str, float]:
        """{column: value} of one run (``complete``: the run ended ok); NaN where :attr:`complete_only` and not complete."""
        if self.complete_only and not complete:
            return dict.fromkeys(self.column_names(name, names), math.nan)
        out = self.compute(result, names)
        if self.columns is None:
            return {name: float(out)}
        return {c: float(out.get(c, math.nan)) for c in self.column_names(name, names)}


def _rmse_columns(names) -> tuple[str, ...]:
    return (*(f"rmse_{n}" for n in names), *(("rmse_position",) if all(n in names for n in POSITION) else ()))


def _rmse(result: SimResult, names) -> dict[str, float]:
    e = result.rmse()
    out = {f"rmse_{n}": e.get(n, math.nan) for n in names}
    if all(n in names for n in POSITION):
        out["rmse_position"] = math.sqrt(sum(e[n] ** 2 for n in POSITION))
    return out


def _x_cm_max(result: SimResult, names) -> float:
    return float(np.max(np.hypot(result.x_cm[:, 0], result.x_cm[:, 1]))) if result.n else math.nan


def _saturation(result: SimResult, names) -> float:
    return result.saturation_fraction()


def _recovery_time(result: SimResult, names) -> float:
    return float(result.metrics.get("recovery_time", math.nan))


def _check(name: str, entry: object) -> None:
    if not isinstance(entry, CampaignMetric):
        raise InputError(f"campaign metric {name!r}: register a qprr.campaign.metrics.CampaignMetric(compute, ...), got {type(entry).__name__}")
    if name in (*BASE_COLUMNS, "success") or name.startswith("rmse_"):
        raise InputError(f"campaign metric {name!r}: the name is a column the campaign keeps itself; choose another name")


METRICS: Registry[CampaignMetric] = Registry("metric", default="rmse", check=_check)
"""Campaign metric name -> :class:`CampaignMetric`: the four below, then the plug-ins' (docs/extending.md)."""
METRICS.register(
    "rmse",
    CampaignMetric(_rmse, "Thesis (6.26) per coordinate, and of the position error norm", "", _rmse_columns, complete_only=True, nonnegative=True),
)
METRICS.register("x_cm_max", CampaignMetric(_x_cm_max, "largest horizontal CoG offset from the thrust axis", "m", nonnegative=True))
METRICS.register(
    "saturation", CampaignMetric(_saturation, "fraction of control ticks with a rotor bound active", "fraction of ticks", nonnegative=True)
)
METRICS.register("recovery_time", CampaignMetric(_recovery_time, "SimResult.metrics['recovery_time'] (payload-drop)", "s", nonnegative=True))

DEFAULT_METRICS = ("rmse", "x_cm_max", "saturation", "recovery_time")
"""The metrics a specification keeps unless it names others: the core's (a plug-in's metric is kept when named)."""


def is_nonnegative(column: str) -> bool:
    """Whether a metric column is >= 0 in every run: ``t_end``, ``wall_time``, the ``rmse_*`` columns and the one-column
    metrics registered ``nonnegative``."""
    if not isinstance(column, str):
        raise InputError(f"column must be a column name (str), got {column!r}")
    if column in ("t_end", "wall_time") or column.startswith("rmse_"):
        return True
    return column in METRICS and METRICS[column].nonnegative and METRICS[column].columns is None


def metric_columns(groups, names, extras=()) -> tuple[str, ...]:
    """Column names of the metrics ``groups`` (names of :data:`METRICS`) for xi ``names``, then ``extras``."""
    for arg, values in (("groups", groups), ("names", names), ("extras", extras)):
        if isinstance(values, str) or not isinstance(values, (list, tuple)) or not all(isinstance(v, str) and v for v in values):
            raise InputError(f"{arg} must be a list of names, got {values!r}")
    for g in groups:
        as_name(g, "groups", tuple(METRICS), kind="metric group")
    out = list(BASE_COLUMNS)
    for g in groups:
        out += METRICS[g].column_names(g, tuple(names))
    return (*out, *extras, "success")


def metrics_of(
    result: SimResult | None,
    groups,
    names,
    extras=(),
    *,
    status: RunStatus | None = None,
    reason: str = "",
    wall_time: float = math.nan,
    success=None,
) -> dict[str, object]:
    """The row of one run: :func:`metric_columns` -> value (the status as its text, a value of :data:`STATUSES`).

    ``result`` may be None (the run raised before simulating); ``status``/``reason`` override
    the result's (e.g. :attr:`RunStatus.ERROR` with the exception text); ``success``: {metric: upper bound}.
    """
    if result is not None and not isinstance(result, SimResult):
        raise InputError(f"result must be a SimResult or None (a run that raised before simulating), got {type(result).__name__}")
    if not (isinstance(wall_time, float) and math.isnan(wall_time)):  # NaN: not measured
        wall_time = as_real(wall_time, "wall_time", nonnegative=True, unit="s")
    row: dict[str, object] = {c: math.nan for c in metric_columns(groups, names, extras)}
    row["success"] = 0
    if result is None:
        row.update(status=run_status(status or RunStatus.ERROR).value, reason=reason, t_end=0.0, wall_time=wall_time)
        return row
    st = run_status(status or result.status)
    row.update(
        status=st.value,
        reason=reason or result.reason,
        wall_time=result.wall_time if math.isnan(wall_time) else wall_time,
        t_end=float(result.t[-1] + result.control_period) if result.n else 0.0,
    )
    for g in groups:
        row.update(METRICS[g].values(g, result, tuple(names), st == RunStatus.OK))
    for k in extras:
        row[k] = float(result.metrics.get(k, math.nan))
    row["success"] = int(st == RunStatus.OK and all(float(row[m]) <= bound for m, bound in (success or {}).items()))
    return row


__all__ = [
    "BASE_COLUMNS",
    "DEFAULT_METRICS",
    "METRICS",
    "POSITION",
    "STATUSES",
    "CampaignMetric",
    "RunStatus",
    "is_nonnegative",
    "metric_columns",
    "run_status",
    "metrics_of",
]
