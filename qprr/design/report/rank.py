"""The ranked table of a study: feasible designs by Pareto level, then by their mean normalised score.

Level 1 is the Pareto front of the feasible designs on the study's objectives (no other
evaluated feasible design is at least as good in every objective and better in one); level 2 the
front of the rest, and so on.  Within a level, designs are ordered by their *score*: each
objective rescaled to [0, 1] over the feasible designs (1 = the best value seen), averaged - a
reading aid, not a preference the study states.  Infeasible and failed designs come last.
"""

from __future__ import annotations

import numpy as np

from ..search.pareto import front_levels
from ..spec.metrics import DESIGN_METRICS, sign


def rows_of(table: np.ndarray) -> list[dict]:
    """The structured table as a list of plain dicts."""
    return [{k: r[k].item() for k in table.dtype.names} for r in table]


def scores(rows: list[dict], objectives) -> np.ndarray:
    """Mean over ``objectives`` of the value rescaled to [0, 1] over ``rows`` (1 = best)."""
    if not rows:
        return np.zeros(0)
    F = np.array([[sign(k) * r[k] for k in objectives] for r in rows], dtype=float)  # to minimise
    lo, hi = F.min(axis=0), F.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    return np.mean((hi - F) / span, axis=1)


def ranked(rows: list[dict], objectives) -> list[dict]:
    """``rows`` with ``level`` and ``score`` added, sorted: feasible by (level, -score, run), then the others by run."""
    good = [dict(r) for r in rows if r["status"] == "ok" and r["feasible"] == 1]
    bad = [dict(r, level=0, score=float("nan")) for r in rows if not (r["status"] == "ok" and r["feasible"] == 1)]
    if good:
        F = np.array([[sign(k) * r[k] for k in objectives] for r in good], dtype=float)
        lv, sc = front_levels(F), scores(good, objectives)
        for r, a, b in zip(good, lv, sc):
            r["level"], r["score"] = int(a), float(b)
    good.sort(key=lambda r: (r["level"], -r["score"], r["run"]))
    return good + sorted(bad, key=lambda r: r["run"])


def front(rows: list[dict], objectives) -> list[dict]:
    """The feasible designs no other evaluated feasible design dominates (level 1 of :func:`ranked`)."""
    return [r for r in ranked(rows, objectives) if r["level"] == 1]


def _fmt(v: float) -> str:
    return f"{v:.4g}" if np.isfinite(v) else "--"


def markdown_table(rows: list[dict], objectives, params=(), limit: int | None = None) -> str:
    """A Markdown table: rank, (2.1) name, level, score, parameters, every metric."""
    cols = [k for k in DESIGN_METRICS]
    head = [
        "rank",
        "design (2.1)",
        "run",
        "front",
        "score",
        *params,
        *[f"{k} [{DESIGN_METRICS[k].unit}]" if DESIGN_METRICS[k].unit else k for k in cols],
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for i, r in enumerate(rows[:limit] if limit else rows, start=1):
        mark = {1: "**1**", 0: "infeasible" if r["status"] == "ok" else r["status"]}.get(r["level"], str(r["level"]))
        cells = [
            str(i),
            r["name"],
            str(r["run"]),
            mark,
            _fmt(r["score"]),
            *[_fmt(r[p]) for p in params],
            *[f"**{_fmt(r[k])}**" if k in objectives else _fmt(r[k]) for k in cols],
        ]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)
