"""The closed-loop check of a design: fly a generic mission with the default controller on the built platform.

:func:`fly_design` (a backend task: plain data in, a dict out) rebuilds the design's platform
and runs the study's ``closed_loop.scenario`` (default ``hover-reach``: climb to 2 m, then move
every arm joint 60 % of the way to its upper limit; :mod:`qprr.scenarios`) with its
``controller`` (default the inverse-dynamics ``idc``), and keeps the campaign metrics
(:func:`qprr.campaign.metrics_of`): the position tracking RMSE (Thesis (6.26)), the largest CoG
offset from the thrust axis and the share of control ticks with a rotor at a thrust bound.
"""

from __future__ import annotations

import math

from ...errors import QprrError
from ...scenarios import SCENARIOS
from ..engine.campaign_io import metrics_of
from ..model.candidate import Candidate, build_candidate
from ..spec.parameters import PARAMETERS
from .task import study_of

FLIGHT_COLUMNS = ("status", "reason", "rmse_position", "x_cm_max", "saturation", "t_end")


def fly_design(spec_dict: dict, row: dict) -> dict:
    """Fly the design of table row ``row`` (``run``, ``kind``, ``architecture``, the parameters); returns the flight metrics."""
    spec = study_of(spec_dict)
    cl = spec.closed_loop
    out = {"run": row["run"], "name": row["name"], **dict.fromkeys(FLIGHT_COLUMNS, math.nan)}
    try:
        if row["kind"] == "reference":
            from ...platforms import load

            platform = load(row["architecture"])
        else:
            platform = build_candidate(Candidate(row["architecture"], {k: float(row[k]) for k in PARAMETERS}), spec.mass)
        result = SCENARIOS[cl.scenario].run(platform=platform, controller=cl.controller, duration=cl.duration)
        m = metrics_of(result, ("rmse", "x_cm_max", "saturation"), platform.xi_names)
    except QprrError as exc:
        out.update(status="failed", reason=f"{type(exc).__name__}: {exc}")
        return out
    out.update({k: m[k] for k in FLIGHT_COLUMNS})
    return out
