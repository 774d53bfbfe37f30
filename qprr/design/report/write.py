"""The report of a design study: ranked table, Pareto figures, closed-loop check of the top designs."""

from __future__ import annotations

import csv
from pathlib import Path

from ...errors import InputError
from ..engine import campaign_io as io
from ..evaluate.flight import FLIGHT_COLUMNS, fly_design
from ..evaluate.task import exclusions
from ..spec.study import DesignSpec
from .figures import parallel_coordinates, pareto_2d
from .rank import markdown_table, ranked, rows_of


def load_study(results) -> tuple[DesignSpec, list[dict]]:
    """The study and its rows from a results file (.csv / .parquet with its .meta.json) or a campaign Results."""
    res = results if isinstance(results, io.Results) else io.read_table(results)
    study = res.meta.get("design_spec")
    if not isinstance(study, dict) or "architectures" not in study:
        raise InputError(f"{str(res.path)!r} holds no design study (run `qprr design run SPEC -o FILE` first)")
    return DesignSpec.from_mapping(study), rows_of(res.table)


def flights(spec: DesignSpec, rows: list[dict], backend="inline", workers=None, scheduler=None) -> list[dict]:
    """The closed-loop check (:func:`~qprr.design.evaluate.flight.fly_design`) of ``rows``, in their order."""
    out: dict[int, dict] = {}
    if not rows:
        return []
    be, owned = io.open_backend(backend, workers, scheduler)
    try:
        io.evaluate_points(
            be,
            fly_design,
            spec.to_dict(),
            rows,
            f"{spec.fingerprint}-flight",
            lambda r: out.__setitem__(r["run"], r),
            lambda p, exc: {"run": p["run"], "name": p["name"], "status": "error", "reason": f"{type(exc).__name__}: {exc}"},
        )
    finally:
        io.close_backend(be, owned)
    return [out[r["run"]] for r in rows]


def _flight_table(rows: list[dict], fl: list[dict]) -> str:
    lines = [
        "| design (2.1) | run | status | position RMSE [mm] | max CoG offset [mm] | rotor saturation [% of ticks] |",
        "|---|---|---|---|---|---|",
    ]
    for r, f in zip(rows, fl):
        ok = f["status"] == "ok"
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
    n_ok = sum(r["status"] == "ok" for r in rows)
    n_feas = sum(r["level"] >= 1 for r in rk)
    n_front = sum(r["level"] == 1 for r in rk)
    head = (
        f"design study {spec.name}: {len(rows)} designs evaluated, {n_ok} ok, {n_feas} feasible, {n_front} on the Pareto front "
        f"of ({', '.join(spec.objectives)})"
    )
    text = [head, *exclusions(rows, spec.constraints), "", markdown_table(rk, spec.objectives, params)]
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
            figures.append(pareto_2d(rk, spec.objectives, d / "pareto.png"))
            figures.append(parallel_coordinates(rk, spec.objectives, d / "parallel.png"))
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
