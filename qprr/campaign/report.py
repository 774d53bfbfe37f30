"""Summaries and figures of a campaign's table (:class:`qprr.campaign.store.Results`).

* :func:`summarize`: per group (default: the controller and the grid parameters) the number of
  runs, the success rate and, over the successful runs, median / mean / 90th percentile / max of
  each metric; :func:`format_table` prints it as text or Markdown.
* :func:`box_plot` (a metric per controller, or per any column), :func:`metric_curve` (a
  metric's median against a swept parameter, per controller), :func:`heat_map` (a metric's
  median or the success rate over two swept parameters, one panel per controller),
  :func:`success_curve` (success rate against a parameter, one curve per controller; a random
  parameter is binned by quantiles), :func:`scatter_plot` (a metric against any parameter).
  Figures go through :func:`qprr.viz.new_figure` (no pyplot).
* :func:`campaign_report`: all of these for a results file, into a folder (``summary.md`` + PNGs).
* :func:`platform_label`: the platform the campaign flew and where it came from (a registered
  name, a (2.1) designation, or a URDF and rotor file with their SHA-256), named in the report's
  header and the figures' titles.  Titles and axis labels are re-wrapped to the page
  (:func:`qprr.viz.fit_texts`), so long column names (``rmse_shoulder_pitch_joint``) are not clipped.
  A figure function given ``path=None`` returns the Figure instead of saving it.

Statistics of a metric are taken over the completed runs (status ``ok``), skipping NaN;
``inf`` (e.g. a payload that never recovers) counts in medians and percentiles.  The success
rate is the mean of the ``success`` column (completed and within the specification's bounds).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError, UnknownNameError
from ..viz import figure_path, fit_texts, new_figure
from .metrics import DEFAULT_METRICS, METRICS, RunStatus
from .store import Results, read_results

if TYPE_CHECKING:
    from matplotlib.figure import Figure

UNITS = {
    "rmse_x": "m",
    "rmse_y": "m",
    "rmse_z": "m",
    "rmse_position": "m",
    "rmse_r0": "m",
    "x_cm_max": "m",
    "saturation": "fraction of ticks",
    "recovery_time": "s",
    "wall_time": "s",
    "t_end": "s",
    "mass": "kg",
    "model.payload": "kg",
    "recovery_peak_position": "m",
    "recovery_peak_angle": "rad",
    "mass_estimate_error": "kg",
    "x": "m",
    "y": "m",
    "z": "m",
    "theta2_d": "rad",
    "noise": "x (6.27) amplitude",
}


def column(results: Results, name: str) -> np.ndarray:
    """A column of the table (:class:`UnknownNameError` lists them)."""
    t = results.table
    if name not in t.dtype.names:
        raise UnknownNameError("results column", name, t.dtype.names)
    return t[name]


def column_units(results: Results) -> dict[str, str]:
    """The units of the arm joints' ``rmse_<joint>`` columns from the joint types the campaign recorded ("m" prismatic,
    "rad" revolute); empty for results that record none (then :func:`_unit`'s defaults apply)."""
    names, kinds = tuple(results.meta.get("names", ())), tuple(results.meta.get("arm_kinds", ()))
    unit = {"prismatic": "m", "revolute": "rad"}
    return {f"rmse_{n}": unit[k] for n, k in zip(names[6:], kinds) if k in unit}


def _unit(name: str, units: dict[str, str] | None = None) -> str | None:
    """The unit of a column (``units`` of :func:`column_units`, :data:`UNITS`; other ``rmse_*`` columns are angles,
    ``model.*`` factors on the nominal value)."""
    u = (units or {}).get(name) or UNITS.get(name)
    if u is None and name in METRICS and METRICS[name].unit:  # a one-column metric registered with its unit
        u = METRICS[name].unit
    if u is None and name.startswith("rmse_"):
        u = "rad"
    if u is None and name.startswith("model."):
        u = "x nominal"
    return u


def _label(name: str, stat: str = "", units: dict[str, str] | None = None) -> str:
    """``name [unit]`` (``name stat [unit]`` with a statistic), or the name alone for a column without unit."""
    u = _unit(name, units)
    name = f"{name} {stat}" if stat else name
    return f"{name} [{u}]" if u else name


def _platform(results: Results):
    """The ``platform`` of the results' specification (a name or a table), None for a store without one."""
    return results.spec.get("platform") if isinstance(results.spec, dict) else None


def platform_name(results: Results) -> str:
    """The platform's short name: its registered name or (2.1) designation, the model name a URDF gave it (recorded by
    :func:`~qprr.campaign.run_campaign`; else the URDF file's stem); "" when the results record no platform."""
    p = _platform(results)
    if isinstance(p, str):
        return p
    if isinstance(p, dict) and "urdf" in p:
        return str(results.meta.get("platform") or Path(str(p["urdf"])).stem)
    return ""


def platform_label(results: Results) -> str:
    """The platform and where it came from: ``NAME (registered platform)``, ``NAME ((2.1) designation)`` or
    ``NAME (URDF FILE sha256 HEX12, rotors FILE sha256 HEX12, ee_frame F)``; "" when the results record none."""
    from ..platforms import NAMES

    p = _platform(results)
    if isinstance(p, str):
        return f"{p} ({'registered platform' if p in NAMES else '(2.1) designation'})"
    if not isinstance(p, dict) or "urdf" not in p:
        return ""
    sha = p.get("sha256") if isinstance(p.get("sha256"), dict) else {}
    files = [f"{'URDF' if k == 'urdf' else k} {p[k]}" + (f" sha256 {str(sha[k])[:12]}" if k in sha else "") for k in ("urdf", "rotors") if k in p]
    if "ee_frame" in p:
        files.append(f"ee_frame {p['ee_frame']}")
    return f"{platform_name(results)} ({', '.join(files)})"


def _head(results: Results) -> str:
    """The start of every figure's title: the campaign's name and, when recorded, its platform."""
    name, platform = results.spec.get("name", ""), platform_name(results)
    return f"{name} on {platform}" if platform else name


def _save(fig, path: Path | None, tight: bool = False):
    """Wrap the texts to the page, then save ``fig`` to ``path`` (returned; ``tight``: cropped to what is drawn), or
    return ``fig`` when ``path`` is None."""
    fit_texts(fig)
    if path is None:
        return fig
    fig.savefig(path, dpi=90, **({"bbox_inches": "tight"} if tight else {}))
    return path


def default_groups(results: Results) -> tuple[str, ...]:
    """The controller and the grid parameters (random ones are what a group averages over)."""
    grid = list(results.spec.get("grid", {}))
    out = [c for c in results.params if c == "controller" or c in grid]
    return tuple(dict.fromkeys(out))


def default_metrics(results: Results) -> tuple[str, ...]:
    """rmse_position, then every one-column metric the specification kept (a plug-in's too) with a finite value."""
    out = []
    names = results.table.dtype.names
    if "rmse_position" in names:
        out.append("rmse_position")
    kept = results.spec.get("metrics", DEFAULT_METRICS) if isinstance(results.spec, dict) else DEFAULT_METRICS
    for m in kept:
        if m != "rmse" and m in names and np.any(np.isfinite(np.asarray(results.table[m], dtype=float))):
            out.append(m)
    return tuple(out)


@dataclass
class Summary:
    """Per-group statistics: ``groups`` (column names), ``rows`` (one dict per group), ``metrics``, ``units`` (of the
    arm joints' columns, :func:`column_units`)."""

    groups: tuple[str, ...]
    metrics: tuple[str, ...]
    rows: list[dict]
    units: dict = field(default_factory=dict)


def summarize(results: Results, by=None, metrics=None) -> Summary:
    """Statistics of ``metrics`` per group of the ``by`` columns (defaults: :func:`default_groups`, :func:`default_metrics`)."""
    by = default_groups(results) if by is None else tuple(by)
    metrics = default_metrics(results) if metrics is None else tuple(metrics)
    keys = [column(results, b) for b in by]
    values = {m: np.asarray(column(results, m), dtype=float) for m in metrics}
    status = results.table["status"] if len(results) else np.array([], dtype=str)
    groups: dict[tuple, list[int]] = {}
    for i in range(len(results)):
        groups.setdefault(tuple(_plain(k[i]) for k in keys), []).append(i)
    rows = []
    for g in sorted(groups, key=lambda x: tuple((0, v) if isinstance(v, (int, float)) else (1, str(v)) for v in x)):
        idx = np.array(groups[g])
        ok = status[idx] == RunStatus.OK
        row = dict(zip(by, g))
        row.update(n=int(idx.size), ok=int(ok.sum()), completed=float(ok.mean()), success=float(_success(results)[idx].mean()))
        reasons = {}
        for r in results.table["reason"][idx][~ok]:
            reasons[str(r).split(":")[0]] = reasons.get(str(r).split(":")[0], 0) + 1
        row["failures"] = ", ".join(f"{k} x{v}" for k, v in sorted(reasons.items(), key=lambda kv: -kv[1]))
        for m in metrics:
            x = values[m][idx][ok]
            x = x[~np.isnan(x)]
            if x.size:  # order statistics without interpolation: inf (never recovered) stays inf
                row[m] = {
                    "median": float(np.median(x) if np.all(np.isfinite(x)) else np.percentile(x, 50, method="nearest")),
                    "mean": float(np.mean(x)),
                    "p90": float(np.percentile(x, 90, method="nearest")),
                    "max": float(np.max(x)),
                }
            else:
                row[m] = None
        rows.append(row)
    return Summary(by, metrics, rows, column_units(results))


def _num(x: float) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if math.isinf(x):
        return "inf"
    return f"{x:.3g}" if abs(x) >= 1e-3 or x == 0 else f"{x:.2e}"


def format_table(summary: Summary, markdown: bool = False, stats=("median", "p90")) -> str:
    """The summary as aligned text (or a Markdown table): group columns, n, success, then metric statistics, with units."""
    head = [*(_label(g, units=summary.units) for g in summary.groups), "n", "completed", "success"]
    for m in summary.metrics:
        head += [_label(m, s, summary.units) for s in stats]
    lines = []
    for row in summary.rows:
        cells = [str(row[g]) if not isinstance(row[g], float) else _num(row[g]) for g in summary.groups]
        cells += [str(row["n"]), f"{100 * row['completed']:.0f} %", f"{100 * row['success']:.0f} %"]
        for m in summary.metrics:
            cells += [_num(row[m][s]) if row[m] else "-" for s in stats]
        lines.append(cells)
    if markdown:
        out = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
        out += ["| " + " | ".join(c) + " |" for c in lines]
        return "\n".join(out)
    widths = [max(len(h), *(len(c[i]) for c in lines)) if lines else len(h) for i, h in enumerate(head)]
    out = ["  ".join(h.rjust(w) for h, w in zip(head, widths)), "  ".join("-" * w for w in widths)]
    out += ["  ".join(c.rjust(w) for c, w in zip(cells, widths)) for cells in lines]
    return "\n".join(out)


# ------------------------------------------------------------------------------ figures
def _ok(results: Results) -> np.ndarray:
    return results.table["status"] == RunStatus.OK


def _success(results: Results) -> np.ndarray:
    t = results.table
    return (np.asarray(t["success"]) == 1) if "success" in t.dtype.names else _ok(results)


def _plain(value):
    """A numpy scalar as the Python value it holds (``value.item()``); any other value as is."""
    return value.item() if isinstance(value, np.generic) else value


def _order(values) -> list:
    u = list(dict.fromkeys(_plain(v) for v in values))
    try:
        return sorted(u)
    except TypeError:
        return u


def box_plot(results: Results, metric: str, path, by: str = "controller", title: str | None = None, log: bool | None = None) -> Path | Figure:
    """Box plot of ``metric`` over the successful runs, one box per value of ``by`` (n and success rate under each)."""
    path = None if path is None else figure_path(path)
    units = column_units(results)
    y = np.asarray(column(results, metric), dtype=float)
    keys = column(results, by)
    ok = _ok(results)
    groups = _order(keys)
    data, labels = [], []
    for g in groups:
        sel = (keys == g) & ok & np.isfinite(y)
        data.append(y[sel])
        n = int((keys == g).sum())
        labels.append(f"{g}\n{int(((keys == g) & ok).sum())}/{n} completed")
    fig = new_figure((max(5.0, 1.6 * len(groups) + 2), 4.5))
    ax = fig.subplots()
    ax.boxplot([d if d.size else np.array([np.nan]) for d in data], showfliers=True)
    ax.set_xticks(range(1, len(groups) + 1), labels)
    finite = np.concatenate([d for d in data if d.size]) if any(d.size for d in data) else np.array([])
    if log is None:
        log = finite.size > 0 and finite.min() > 0 and finite.max() / finite.min() > 100
    if log:
        ax.set_yscale("log")
    ax.set_ylabel(_label(metric, units=units))
    ax.set_xlabel(_label(by, units=units))
    ax.grid(alpha=0.3, axis="y")
    ax.set_title(title or f"{_head(results)}: {metric} per {by} (completed runs)")
    return _save(fig, path)


def heat_map(
    results: Results, x: str, y: str, path, metric: str = "success", by: str | None = "controller", title: str | None = None
) -> Path | Figure:
    """Median of ``metric`` (or the success rate, ``metric="success"``) over the grid of ``x`` and ``y``, one panel per ``by`` value."""
    path = None if path is None else figure_path(path)
    units = column_units(results)
    xs, ys = column(results, x), column(results, y)
    xv, yv = _order(xs), _order(ys)
    if len(xv) > 40 or len(yv) > 40:
        raise InputError(f"heat maps need swept (grid) parameters: {x!r} has {len(xv)} values, {y!r} {len(yv)}")
    panels = _order(column(results, by)) if by else [None]
    ok = _ok(results)
    won = _success(results)
    vals = None if metric == "success" else np.asarray(column(results, metric), dtype=float)
    fig = new_figure((4.2 * len(panels) + 1.2, 4.0))
    axes = np.atleast_1d(fig.subplots(1, len(panels), squeeze=False)[0])
    grids = []
    for p in panels:
        sel_p = np.ones(len(results), bool) if p is None else column(results, by) == p
        Z = np.full((len(yv), len(xv)), np.nan)
        for i, yy in enumerate(yv):
            for j, xx in enumerate(xv):
                sel = sel_p & (xs == xx) & (ys == yy)
                if not sel.any():
                    continue
                if vals is None:
                    Z[i, j] = won[sel].mean()
                else:
                    z = vals[sel & ok]
                    z = z[~np.isnan(z)]
                    Z[i, j] = np.median(z) if z.size else np.nan
        grids.append(Z)
    finite = np.concatenate([Z[np.isfinite(Z)] for Z in grids]) if grids else np.array([])
    vmin, vmax = (0.0, 1.0) if vals is None else ((finite.min(), finite.max()) if finite.size else (0.0, 1.0))
    use_log = vals is not None and finite.size and finite.min() > 0 and vmax / vmin > 100
    from matplotlib.colors import LogNorm, Normalize

    norm = LogNorm(vmin, vmax) if use_log else Normalize(vmin, vmax)
    im = None
    for ax, p, Z in zip(axes, panels, grids):
        im = ax.imshow(Z, origin="lower", aspect="auto", cmap="viridis" if vals is not None else "RdYlGn", norm=norm)
        ax.set_xticks(range(len(xv)), [_num(v) if isinstance(v, float) else str(v) for v in xv], rotation=45)
        ax.set_yticks(range(len(yv)), [_num(v) if isinstance(v, float) else str(v) for v in yv])
        ax.set_xlabel(_label(x, units=units))
        ax.set_ylabel(_label(y, units=units))
        ax.set_title(str(p) if p is not None else "")
        for i in range(len(yv)):
            for j in range(len(xv)):
                if np.isfinite(Z[i, j]):
                    ax.text(
                        j,
                        i,
                        f"{100 * Z[i, j]:.0f}%" if vals is None else _num(Z[i, j]),
                        ha="center",
                        va="center",
                        fontsize=7,
                        color="w" if norm(Z[i, j]) < 0.5 else "k",
                    )
    fig.colorbar(im, ax=list(axes), label="success rate" if vals is None else f"median {_label(metric, units=units)}")
    fig.suptitle(title or f"{_head(results)}: {'success rate' if vals is None else 'median ' + metric} over {x} x {y}")
    return _save(fig, path, tight=True)


def success_curve(results: Results, x: str, path, by: str | None = "controller", bins: int = 8, title: str | None = None) -> Path | Figure:
    """Success rate against ``x``, one curve per ``by`` value (a parameter with many values is binned by quantiles)."""
    path = None if path is None else figure_path(path)
    units = column_units(results)
    xs = np.asarray(column(results, x), dtype=float)
    ok = _success(results)
    values = np.unique(xs)
    if values.size > bins:
        edges = np.unique(np.quantile(xs, np.linspace(0, 1, bins + 1)))
        idx = np.clip(np.searchsorted(edges, xs, side="right") - 1, 0, edges.size - 2)
        centers = np.array([xs[idx == k].mean() if np.any(idx == k) else np.nan for k in range(edges.size - 1)])
    else:
        idx = np.searchsorted(values, xs)
        centers = values
    fig = new_figure((6.5, 4.2))
    ax = fig.subplots()
    panels = _order(column(results, by)) if by else [None]
    for p in panels:
        sel_p = np.ones(len(results), bool) if p is None else column(results, by) == p
        rate = [ok[sel_p & (idx == k)].mean() if np.any(sel_p & (idx == k)) else np.nan for k in range(centers.size)]
        ax.plot(centers, rate, "o-", label=str(p) if p is not None else None)
    ax.set_ylim(-0.03, 1.03)
    ax.set_xlabel(_label(x, units=units))
    ax.set_ylabel("success rate")
    ax.grid(alpha=0.3)
    if by:
        ax.legend(title=by)
    ax.set_title(title or f"{_head(results)}: success rate against {x}")
    return _save(fig, path)


def metric_curve(
    results: Results, x: str, metric: str, path, by: str | None = "controller", title: str | None = None, log: bool | None = None
) -> Path | Figure:
    """Median of ``metric`` against the swept parameter ``x`` (band: 25th-75th percentile), one curve per ``by`` value.

    Completed runs only; ``inf`` values (e.g. never recovered) are drawn at the top edge as crosses."""
    path = None if path is None else figure_path(path)
    units = column_units(results)
    xs = np.asarray(column(results, x), dtype=float)
    ys = np.asarray(column(results, metric), dtype=float)
    ok = _ok(results)
    values = np.unique(xs)
    if values.size > 40:
        raise InputError(f"metric curves need a swept (grid) parameter: {x!r} has {values.size} values")
    fig = new_figure((6.5, 4.2))
    ax = fig.subplots()
    panels = _order(column(results, by)) if by else [None]
    finite_all = ys[ok & np.isfinite(ys)]
    if log is None:
        log = finite_all.size > 0 and finite_all.min() > 0 and finite_all.max() / finite_all.min() > 100
    top = finite_all.max() * (3.0 if log else 1.1) if finite_all.size else 1.0
    any_inf = False
    for k, p in enumerate(panels):
        sel_p = ok if p is None else ok & (column(results, by) == p)
        med, lo, hi, infs = [], [], [], []
        for v in values:
            z = ys[sel_p & (xs == v)]
            infs.append(bool(np.any(np.isposinf(z))))
            z = z[~np.isnan(z)]
            med.append(np.percentile(z, 50, method="nearest") if z.size else np.nan)
            lo.append(np.percentile(z, 25, method="nearest") if z.size else np.nan)
            hi.append(np.percentile(z, 75, method="nearest") if z.size else np.nan)
        med, lo, hi = (np.where(np.isposinf(a), np.nan, a) for a in (np.array(med), np.array(lo), np.array(hi)))
        (line,) = ax.plot(values, med, "o-", label=str(p) if p is not None else None)
        ax.fill_between(values, lo, hi, color=line.get_color(), alpha=0.15)
        if any(infs):  # a cross per curve at the top edge, staggered so that curves do not hide each other
            any_inf = True
            y_inf = top * (1.25**k if log else 1.0 + 0.04 * k)
            ax.plot(values[np.array(infs)], np.full(int(np.sum(infs)), y_inf), "x", color=line.get_color(), ms=8)
    if any_inf:
        ax.plot([], [], "kx", label="inf (e.g. never recovered)")
    if log:
        ax.set_yscale("log")
    ax.set_xlabel(_label(x, units=units))
    ax.set_ylabel(f"median {_label(metric, units=units)}")
    ax.grid(alpha=0.3)
    if by:
        ax.legend(title=by, fontsize=8)
    ax.set_title(title or f"{_head(results)}: {metric} against {x} (completed runs)", fontsize=10)
    return _save(fig, path)


def scatter_plot(
    results: Results, x: str, metric: str, path, by: str | None = "controller", title: str | None = None, log: bool | None = None
) -> Path | Figure:
    """``metric`` against any parameter ``x`` (e.g. a random one), one colour per ``by`` value; completed runs."""
    path = None if path is None else figure_path(path)
    units = column_units(results)
    xs = np.asarray(column(results, x), dtype=float)
    ys = np.asarray(column(results, metric), dtype=float)
    ok = _ok(results) & np.isfinite(ys)
    fig = new_figure((6.5, 4.2))
    ax = fig.subplots()
    panels = _order(column(results, by)) if by else [None]
    for p in panels:
        sel = ok if p is None else ok & (column(results, by) == p)
        ax.plot(xs[sel], ys[sel], "o", ms=4, alpha=0.7, label=f"{by} = {p}" if p is not None else None)
    y = ys[ok]
    if log is None:
        log = y.size > 0 and y.min() > 0 and y.max() / y.min() > 100
    if log:
        ax.set_yscale("log")
    ax.set_xlabel(_label(x, units=units))
    ax.set_ylabel(_label(metric, units=units))
    ax.grid(alpha=0.3)
    if by:
        ax.legend(fontsize=8)
    ax.set_title(title or f"{_head(results)}: {metric} against {x} (completed runs)", fontsize=10)
    return _save(fig, path)


def _numeric(results: Results, name: str) -> bool:
    return results.table[name].dtype.kind in "fiu"


def planned_runs(results: Results) -> int:
    """The number of runs the campaign has (its ``.meta.json``'s ``n_runs``; the rows read when it does not say)."""
    n = results.meta.get("n_runs")
    return n if isinstance(n, int) and not isinstance(n, bool) and n >= len(results) else len(results)


def _headline(res: Results, on: str, crit: str) -> str:
    """The first line, "NAME: 3 of 4 runs of SCENARIO (1 missing ...), 3 completed (75.0 % of 4) ...": percentages of the campaign's
    runs, a missing run (never run, or its record cut) counted as missing, not as completed."""
    n = planned_runs(res)
    what = f"{res.spec.get('name', '')}: {len(res)} of {n} runs of {res.spec.get('scenario') or res.spec.get('callable')}{on}"
    if not n:
        return f"{what}: no runs"
    missing = n - len(res)
    if missing:
        what += (
            f" ({missing} missing: not run yet, or a record cut by an interrupted write; `qprr campaign run` with the "
            f"same specification and output runs them)"
        )
    ok, good = int(_ok(res).sum()) if len(res) else 0, int(_success(res).sum()) if len(res) else 0
    return f"{what}, {ok} completed ({100 * ok / n:.1f} % of {n}), {good} successful ({100 * good / n:.1f} %){crit}"


def not_ok_reasons(results: Results, limit: int = 3) -> list[str]:
    """One line per distinct reason of the runs that did not complete (most frequent first, at most ``limit``): what
    the ``reason`` column of the table says, on the terminal (a typo in an option fails every run with one reason)."""
    if not len(results) or "reason" not in results.table.dtype.names:
        return []
    status, reason = results.table["status"], results.table["reason"]
    bad = status != RunStatus.OK
    if not bad.any():
        return []
    keys, counts = np.unique(np.char.add(np.char.add(status[bad], ": "), reason[bad]), return_counts=True)
    order = np.argsort(-counts, kind="stable")
    lines = [f"  {counts[k]} run(s) {keys[k]}" for k in order[:limit]]
    if len(order) > limit:
        lines.append(f"  ... and {int(counts[order[limit:]].sum())} run(s) with {len(order) - limit} other reason(s) (the table's reason column)")
    return [f"not completed ({int(bad.sum())} run(s)):", *lines]


def campaign_report(
    path_or_results, out: str | Path | None = None, *, by=None, metrics=None, heatmap=None, curve=None, scatter=None, markdown: bool = False
) -> tuple[str, list[Path]]:
    """Summary text (and, with ``out``, ``summary.md`` and the figures in that folder); returns (text, figure paths).

    Figures: a box plot per metric (per controller, if there is one); a success-rate curve per
    numeric parameter that varies (or ``curve``); a metric curve per metric against the first
    numeric grid parameter; a heat map of the success rate and of the first metric over
    ``heatmap`` = (x, y), default the first two numeric grid parameters; ``scatter`` = (x,
    metric) pairs: scatter plots coloured by ``by`` (the first group column).
    """
    res = path_or_results if isinstance(path_or_results, Results) else read_results(path_or_results)
    summ = summarize(res, by, metrics)
    text = format_table(summ, markdown=markdown)
    bounds = res.spec.get("success") or {}
    crit = ("; success: completed and " + ", ".join(f"{k} <= {v:g}" for k, v in bounds.items())) if bounds else ""
    platform = platform_label(res)
    on = f" on {platform}" if platform else ""
    head = "\n".join([_headline(res, on, crit), *not_ok_reasons(res)])
    text = head + "\n" + text
    figures: list[Path] = []
    if out is None or not len(res):
        return text, figures
    out = Path(out)
    if not out.parent.is_dir():
        raise InputError(f"cannot write the report into {str(out)!r}: folder {str(out.parent)!r} does not exist")
    out.mkdir(exist_ok=True)
    stem = res.spec.get("name", "campaign")
    by_ctrl = "controller" if "controller" in res.params else None
    for m in summ.metrics:
        if by_ctrl:
            figures.append(box_plot(res, m, out / f"{stem}-box-{m}.png", by=by_ctrl))
    varying = [p for p in res.params if p != "controller" and _numeric(res, p) and np.unique(res.table[p]).size > 1]
    for x in [curve] if curve else varying:
        figures.append(success_curve(res, x, out / f"{stem}-success-{x}.png", by=by_ctrl))
    grid = [p for p in res.params if p in res.spec.get("grid", {}) and p != "controller" and _numeric(res, p)]
    if grid:
        for m in summ.metrics:
            figures.append(metric_curve(res, grid[0], m, out / f"{stem}-curve-{m}.png", by=by_ctrl))
    hm = tuple(heatmap) if heatmap else (tuple(grid[:2]) if len(grid) >= 2 else None)
    if hm:
        hb = None if "controller" in hm else by_ctrl
        figures.append(heat_map(res, hm[0], hm[1], out / f"{stem}-heat-success.png", by=hb))
        if summ.metrics:
            figures.append(heat_map(res, hm[0], hm[1], out / f"{stem}-heat-{summ.metrics[0]}.png", metric=summ.metrics[0], by=hb))
    colour = summ.groups[0] if summ.groups else None
    for x, m in scatter or ():
        figures.append(scatter_plot(res, x, m, out / f"{stem}-scatter-{m}-{x}.png", by=colour))
    md = [f"# {stem}", "", head, "", format_table(summ, markdown=True), ""]
    md += [f"![{p.stem}]({p.name})" for p in figures]
    (out / "summary.md").write_text("\n".join(md) + "\n")
    return text, figures
