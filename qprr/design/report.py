"""Answers people can read: the ranked table, Pareto figures, the closed-loop check of the top designs, the report.

**Ranking.** The ranked table of a study: feasible designs by Pareto level, then by their mean normalised score.

Level 1 is the Pareto front of the feasible designs on the study's objectives (no other
evaluated feasible design is at least as good in every objective and better in one); level 2 the
front of the rest, and so on.  Within a level, designs are ordered by their *score*: each
objective rescaled to [0, 1] over the feasible designs (1 = the best value seen), averaged - a
reading aid, not a preference the study states.  Infeasible and failed designs come last.

**Figures.** Figures of a design study: Pareto fronts in 2-D and parallel coordinates (matplotlib, Agg).

**The closed-loop check.** The closed-loop check of a design: fly a generic mission with the default controller on the built platform.

:func:`fly_design` (a backend task: plain data in, a dict out) rebuilds the design's platform
and runs the study's ``closed_loop.scenario`` (default ``hover-reach``: climb to 2 m, then move
every arm joint 60 % of the way to its upper limit; :mod:`qprr.scenarios`) with its
``controller`` (default the inverse-dynamics ``idc``), and keeps the campaign metrics
(:func:`qprr.campaign.metrics_of`): the position tracking RMSE (Thesis (6.26)), the largest CoG
offset from the thrust axis and the share of control ticks with a rotor at a thrust bound.

**The report.** The report of a design study: ranked table, Pareto figures, closed-loop check of the top designs.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from ..campaign import metrics_of
from ..campaign.metrics import RunStatus
from ..errors import InputError, QprrError
from ..nomenclature import parse
from ..scenarios import SCENARIOS
from .evaluate import design_platform, exclusions, params_of_row, study_of
from .metrics import DESIGN_METRICS, label, sign
from .search import Results, close_backend, dominated, evaluate_points, front_levels, open_backend, read_table
from .spec import DesignSpec, StudyKind


# ---------------------------------------------------------------------------------------------------- Ranking
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
    good = [dict(r) for r in rows if r["status"] == RunStatus.OK and r["feasible"] == 1]
    bad = [dict(r, level=0, score=float("nan")) for r in rows if not (r["status"] == RunStatus.OK and r["feasible"] == 1)]
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


def _fmt(v: float | str) -> str:
    """A cell of the Markdown table: a number to 4 digits, a word as it is, "--" where nothing applies."""
    if isinstance(v, str):
        return v or "--"
    return f"{v:.4g}" if np.isfinite(v) else "--"


def markdown_table(rows: list[dict], objectives, params=(), limit: int | None = None) -> str:
    """A Markdown table: rank, (2.1) name, level, score, parameters, every metric."""
    cols = [k for k in DESIGN_METRICS]
    head = [
        "rank",
        "design",
        "run",
        "front",
        "score",
        *params,
        *[f"{k} [{DESIGN_METRICS[k].unit}]" if DESIGN_METRICS[k].unit else k for k in cols],
    ]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for i, r in enumerate(rows[:limit] if limit else rows, start=1):
        mark = {1: "**1**", 0: "infeasible" if r["status"] == RunStatus.OK else r["status"]}.get(r["level"], str(r["level"]))
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


# ---------------------------------------------------------------------------------------------------- Figures
MARKERS = {"Q": "o", "HEX": "s", "OCT": "D"}
"""Marker of each vehicle (Table 2.3 code) in a nomenclature study; the colour is the arm's joint sequence."""


def _group(row: dict, kind: StudyKind, colour_by: str | None) -> str:
    """The colour's legend entry of a design: the value of parameter ``colour_by`` when given, else its arm (a
    nomenclature study) or its robot (a URDF study)."""
    if colour_by is not None:
        v = row[colour_by]
        return f"{colour_by} = {v:.4g}" if isinstance(v, float) and np.isfinite(v) else f"{colour_by} = {v or 'n/a'}"
    return f"arm {row['architecture'].split('-')[-1]}" if kind is StudyKind.NOMENCLATURE else row["architecture"]


def _vehicle(row: dict, kind: StudyKind) -> str:
    """The marker's legend entry: the vehicle of a nomenclature study's design, "" in a URDF study (one robot)."""
    return parse(row["architecture"]).uav if kind is StudyKind.NOMENCLATURE else ""


def _in_order(v: float | str) -> tuple:
    """Sort key of a parameter's values: numbers in their order, then words, then the cells where it does not apply."""
    if isinstance(v, float):
        return (0, v, "") if np.isfinite(v) else (2, 0.0, "")
    return (1, 0.0, v) if v else (2, 0.0, "")


def _colours(rows, kind: StudyKind, colour_by: str | None):
    import matplotlib

    designs = [r for r in rows if r["kind"] != "reference"]
    if colour_by is None:
        groups = sorted({_group(r, kind, None) for r in designs})
    else:
        groups = list(dict.fromkeys(_group(r, kind, colour_by) for r in sorted(designs, key=lambda r: _in_order(r[colour_by]))))
    cmap = matplotlib.colormaps["tab10"]
    return {a: cmap(i % 10) for i, a in enumerate(groups)}


def _legend(fig, colours, vehicles, references) -> int:
    """The figure's legend: the colours, the vehicles' markers, a star per reference the study names, the front's ring."""
    from matplotlib.lines import Line2D

    h = [Line2D([], [], ls="", marker="o", color=c, label=a) for a, c in colours.items()]
    h += [Line2D([], [], ls="", marker=MARKERS.get(v, "o"), color="0.4", label=f"{v} vehicle") for v in vehicles]
    h += [Line2D([], [], ls="", marker="*", markersize=12, color="k", label=name) for name in references]
    h.append(Line2D([], [], ls="", marker="o", markersize=9, markerfacecolor="none", markeredgecolor="k", label="Pareto front (all objectives)"))
    fig.legend(handles=h, loc="lower center", ncol=min(6, len(h)), fontsize=8, frameon=False)
    return len(h)


def pareto_2d(rows: list[dict], objectives, path, pairs=None, kind: StudyKind = StudyKind.NOMENCLATURE, colour_by: str | None = None) -> str:
    """Scatter panels of ``objectives[0]`` against each other objective (or ``pairs``): every feasible
    design coloured by the value of parameter ``colour_by``, or by arm (``kind``: a nomenclature study; by robot in a
    URDF study), the study's Pareto front (all objectives) ringed in black, each panel's own 2-D front as a step line,
    the references the study names as stars."""
    from matplotlib.figure import Figure  # not attached to pyplot: no backend chosen, nothing to close

    ok = [r for r in rows if r["status"] == RunStatus.OK and r.get("level", 0) >= 1]
    pairs = pairs or [(objectives[0], k) for k in objectives[1:]]
    n = len(pairs)
    ncol = min(n, 2)
    nrow = int(np.ceil(n / ncol))
    fig = Figure(figsize=(6.4 * ncol, 4.6 * nrow))
    axes = fig.subplots(nrow, ncol, squeeze=False)
    col = _colours(ok, kind, colour_by)
    vehicles = sorted({_vehicle(r, kind) for r in ok if r["kind"] != "reference"} - {""})
    references = list(dict.fromkeys(r["name"] for r in ok if r["kind"] == "reference"))
    for ax, (kx, ky) in zip(axes.flat, pairs):
        x = np.array([r[kx] for r in ok])
        y = np.array([r[ky] for r in ok])
        for r, a, b in zip(ok, x, y):
            if r["kind"] == "reference":
                ax.scatter(a, b, s=220, marker="*", color="k", zorder=5)
            else:
                ax.scatter(a, b, s=34, marker=MARKERS.get(_vehicle(r, kind), "o"), color=col[_group(r, kind, colour_by)], alpha=0.85, zorder=2)
        lv1 = np.array([r["level"] == 1 for r in ok])
        ax.scatter(x[lv1], y[lv1], s=110, facecolor="none", edgecolor="k", linewidth=1.0, zorder=3)
        nd = ~dominated(np.c_[sign(kx) * x, sign(ky) * y])
        order = np.argsort(x[nd])
        ax.plot(x[nd][order], y[nd][order], color="0.35", lw=0.9, ls=":", zorder=1)
        ax.set_xlabel(label(kx))
        ax.set_ylabel(label(ky))
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    nh = _legend(fig, col, vehicles, references)
    fig.tight_layout(rect=(0, 0.035 * int(np.ceil(nh / 6)), 1, 1))
    fig.savefig(path, dpi=110)
    return str(path)


def parallel_coordinates(rows: list[dict], objectives, path, kind: StudyKind = StudyKind.NOMENCLATURE, colour_by: str | None = None) -> str:
    """One line per feasible design across the objectives (each axis from its worst to its best value seen):
    the Pareto front coloured as in :func:`pareto_2d` (solid: Q, dash-dot: HEX), the other designs grey, references
    dashed black."""
    from matplotlib.figure import Figure  # not attached to pyplot: no backend chosen, nothing to close

    ok = [r for r in rows if r["status"] == RunStatus.OK and r.get("level", 0) >= 1]
    F = np.array([[r[k] for k in objectives] for r in ok], dtype=float)
    lo, hi = F.min(axis=0), F.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    worst = np.where([DESIGN_METRICS[k].better == "max" for k in objectives], lo, hi)
    Z = np.abs(F - worst) / span  # 0 worst, 1 best
    fig = Figure(figsize=(2.1 * len(objectives) + 2.5, 5.0))
    ax = fig.subplots()
    col = _colours(ok, kind, colour_by)
    xs = np.arange(len(objectives))
    for z, r in zip(Z, ok):
        if r["level"] != 1 and r["kind"] != "reference":
            ax.plot(xs, z, color="0.82", lw=0.7, zorder=1)
    seen = set()
    for z, r in zip(Z, ok):
        if r["kind"] == "reference":
            ax.plot(xs, z, color="k", lw=2.0, ls="--", zorder=4, label=r["name"])
        elif r["level"] == 1:
            a = r["architecture"] if kind is StudyKind.NOMENCLATURE else _group(r, kind, colour_by)
            ls = {"": "-", "Q": "-", "HEX": "-."}.get(_vehicle(r, kind), ":")
            ax.plot(xs, z, color=col[_group(r, kind, colour_by)], ls=ls, lw=1.6, zorder=3, label=None if a in seen else a)
            seen.add(a)
    best = np.where([DESIGN_METRICS[k].better == "max" for k in objectives], hi, lo)
    ax.set_xticks(xs, [f"{label(k)}\nworst {w:.3g}\nbest {b:.3g}" for k, w, b in zip(objectives, worst, best)], fontsize=8)
    ax.set_ylabel("normalised: 0 worst, 1 best seen")
    ax.set_ylim(-0.03, 1.03)
    for x in xs:
        ax.axvline(x, color="0.5", lw=0.6)
    ax.legend(loc="center left", bbox_to_anchor=(1.0, 0.5), fontsize=8, frameon=False, title="Pareto front")
    ax.set_title("designs across the objectives (grey: dominated)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    return str(path)


# -------------------------------------------------------------------------------------- The closed-loop check
FLIGHT_COLUMNS = ("status", "reason", "rmse_position", "x_cm_max", "saturation", "t_end")


def fly_design(spec_dict: dict, row: dict) -> dict:
    """Fly the design of table row ``row`` (``run``, ``kind``, ``architecture``, the parameters); returns the flight metrics."""
    spec = study_of(spec_dict)
    cl = spec.closed_loop
    out = {"run": row["run"], "name": row["name"], **dict.fromkeys(FLIGHT_COLUMNS, math.nan)}
    try:
        params = params_of_row(spec, row) if row["kind"] != "reference" else {}
        platform = design_platform(spec, row["kind"], row["architecture"], params)
        result = SCENARIOS[cl.scenario].run(platform=platform, controller=cl.controller, duration=cl.duration)
        m = metrics_of(result, ("rmse", "x_cm_max", "saturation"), platform.xi_names)
    except QprrError as exc:
        out.update(status=RunStatus.FAILED, reason=f"{type(exc).__name__}: {exc}")
        return out
    out.update({k: m[k] for k in FLIGHT_COLUMNS})
    return out


# ------------------------------------------------------------------------------------------------- The report
def load_study(results) -> tuple[DesignSpec, list[dict]]:
    """The study and its rows from a results file (.csv / .parquet with its .meta.json) or a campaign Results."""
    res = results if isinstance(results, Results) else read_table(results)
    study = res.meta.get("design_spec")
    if not isinstance(study, dict) or "objectives" not in study:
        raise InputError(f"{str(res.path)!r} holds no design study (run `qprr design run SPEC -o FILE` first)")
    return DesignSpec.from_mapping(study), rows_of(res.table)


def flights(spec: DesignSpec, rows: list[dict], backend="inline", workers=None, scheduler=None) -> list[dict]:
    """The closed-loop check (:func:`~qprr.design.report.fly_design`) of ``rows``, in their order."""
    out: dict[int, dict] = {}
    if not rows:
        return []
    be, owned = open_backend(backend, workers, scheduler)
    try:
        evaluate_points(
            be,
            fly_design,
            spec.to_dict(),
            rows,
            f"{spec.fingerprint}-flight",
            lambda r: out.__setitem__(r["run"], r),
            lambda p, exc: {"run": p["run"], "name": p["name"], "status": RunStatus.ERROR, "reason": f"{type(exc).__name__}: {exc}"},
        )
    finally:
        close_backend(be, owned)
    return [out[r["run"]] for r in rows]


def _flight_table(rows: list[dict], fl: list[dict]) -> str:
    lines = [
        "| design | run | status | position RMSE [mm] | max CoG offset [mm] | rotor saturation [% of ticks] |",
        "|---|---|---|---|---|---|",
    ]
    for r, f in zip(rows, fl):
        ok = f["status"] == RunStatus.OK
        lines.append(
            f"| {r['name']} | {r['run']} | {f['status']} | "
            + (
                " | ".join([f"{1000 * f['rmse_position']:.3f}", f"{1000 * f['x_cm_max']:.2f}", f"{100 * f['saturation']:.2f}"])
                if ok
                else f"{f.get('reason', '')[:60]} | -- | --"
            )
            + " |"
        )
    return "\n".join(lines)


def design_report(results, out=None, *, top: int | None = None, fly: bool = True, backend="inline", workers=None, scheduler=None):
    """Ranked table (Markdown text) and, with ``out``, ``summary.md``, ``ranking.csv``, ``closed_loop.csv`` and the figures.

    ``top``: designs flown in the closed-loop check (default the study's ``closed_loop.top``; the
    references are flown too).  Returns ``(text, figure paths)``.
    """
    spec, rows = load_study(results)
    rk = ranked(rows, spec.objectives)
    params = spec.optimised or spec.swept
    n_ok = sum(r["status"] == RunStatus.OK for r in rows)
    n_feas = sum(r["level"] >= 1 for r in rk)
    n_front = sum(r["level"] == 1 for r in rk)
    head = (
        f"design study {spec.name}: {len(rows)} designs evaluated, {n_ok} ok, {n_feas} feasible, {n_front} on the Pareto front "
        f"of ({', '.join(spec.objectives)})"
    )
    text = [head, *exclusions(rows, spec), "", markdown_table(rk, spec.objectives, params)]
    figures: list[str] = []
    k = spec.closed_loop.top if top is None else top
    chosen = [r for r in rk if r["level"] >= 1 and r["kind"] != "reference"][:k] + [r for r in rk if r["kind"] == "reference"]
    fl = flights(spec, chosen, backend, workers, scheduler) if fly and chosen else []
    if fl:
        text += [
            "",
            f"closed-loop check: {spec.closed_loop.scenario} with {spec.closed_loop.controller}, {spec.closed_loop.duration:g} s",
            "",
            _flight_table(chosen, fl),
        ]
    if out is not None:
        d = Path(out)
        if d.exists() and not d.is_dir():
            raise InputError(f"out: {str(d)!r} is a file, not a folder for the report")
        d.mkdir(parents=True, exist_ok=True)
        if sum(r["level"] >= 1 for r in rk) >= 2:
            colour_by = spec.swept[-1] if spec.kind is StudyKind.URDF and spec.swept else None  # the robot is one: its grid's last axis
            figures.append(pareto_2d(rk, spec.objectives, d / "pareto.png", kind=spec.kind, colour_by=colour_by))
            figures.append(parallel_coordinates(rk, spec.objectives, d / "parallel.png", kind=spec.kind, colour_by=colour_by))
        _csv(d / "ranking.csv", rk)
        if fl:
            _csv(d / "closed_loop.csv", fl, ("run", "name", *FLIGHT_COLUMNS))
        (d / "summary.md").write_text("\n".join(text) + "\n" + "".join(f"\n![{Path(f).stem}]({Path(f).name})\n" for f in figures))
    return "\n".join(text), figures


def _csv(path: Path, rows: list[dict], cols=None) -> None:
    cols = list(cols or rows[0].keys())
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for r in rows:
            w.writerow([repr(r[c]) if isinstance(r[c], float) else r[c] for c in cols])
