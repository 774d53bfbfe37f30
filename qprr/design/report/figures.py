"""Figures of a design study: Pareto fronts in 2-D and parallel coordinates (matplotlib, Agg)."""

from __future__ import annotations

import numpy as np

from ...nomenclature import parse
from ..search.pareto import dominated
from ..spec.metrics import DESIGN_METRICS, label, sign

MARKERS = {"Q": "o", "HEX": "s", "OCT": "D"}
"""Marker of each vehicle (Table 2.3 code); the colour is the arm's joint sequence."""


def _arm(row: dict) -> str:
    return row["architecture"].split("-")[-1] if row["kind"] != "reference" else "reference"


def _vehicle(row: dict) -> str:
    return parse(row["architecture"]).uav if row["kind"] != "reference" else "reference"


def _colours(rows):
    import matplotlib

    arms = sorted({_arm(r) for r in rows} - {"reference"})
    cmap = matplotlib.colormaps["tab10"]
    return {a: cmap(i % 10) for i, a in enumerate(arms)}


def _legend(fig, axes, colours, vehicles) -> int:
    from matplotlib.lines import Line2D

    h = [Line2D([], [], ls="", marker="o", color=c, label=f"arm {a}") for a, c in colours.items()]
    h += [Line2D([], [], ls="", marker=MARKERS.get(v, "o"), color="0.4", label=f"{v} vehicle") for v in vehicles]
    h += [
        Line2D([], [], ls="", marker="*", markersize=12, color="k", label="thesis Q-PRR (stored)"),
        Line2D([], [], ls="", marker="o", markersize=9, markerfacecolor="none", markeredgecolor="k", label="Pareto front (all objectives)"),
    ]
    fig.legend(handles=h, loc="lower center", ncol=min(6, len(h)), fontsize=8, frameon=False)
    return len(h)


def pareto_2d(rows: list[dict], objectives, path, pairs=None) -> str:
    """Scatter panels of ``objectives[0]`` against each other objective (or ``pairs``): every feasible
    design coloured by architecture, the study's Pareto front (all objectives) ringed in black, each
    panel's own 2-D front as a step line, references as stars."""
    from matplotlib.figure import Figure  # not attached to pyplot: no backend chosen, nothing to close

    ok = [r for r in rows if r["status"] == "ok" and r.get("level", 0) >= 1]
    pairs = pairs or [(objectives[0], k) for k in objectives[1:]]
    n = len(pairs)
    ncol = min(n, 2)
    nrow = int(np.ceil(n / ncol))
    fig = Figure(figsize=(6.4 * ncol, 4.6 * nrow))
    axes = fig.subplots(nrow, ncol, squeeze=False)
    col = _colours(ok)
    vehicles = sorted({_vehicle(r) for r in ok} - {"reference"})
    for ax, (kx, ky) in zip(axes.flat, pairs):
        x = np.array([r[kx] for r in ok])
        y = np.array([r[ky] for r in ok])
        for r, a, b in zip(ok, x, y):
            if r["kind"] == "reference":
                ax.scatter(a, b, s=220, marker="*", color="k", zorder=5)
            else:
                ax.scatter(a, b, s=34, marker=MARKERS.get(_vehicle(r), "o"), color=col[_arm(r)], alpha=0.85, zorder=2)
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
    nh = _legend(fig, axes, col, vehicles)
    fig.tight_layout(rect=(0, 0.035 * int(np.ceil(nh / 6)), 1, 1))
    fig.savefig(path, dpi=110)
    return str(path)


def parallel_coordinates(rows: list[dict], objectives, path) -> str:
    """One line per feasible design across the objectives (each axis from its worst to its best value seen):
    the Pareto front coloured by arm (solid: Q, dash-dot: HEX), the other designs grey, references dashed black."""
    from matplotlib.figure import Figure  # not attached to pyplot: no backend chosen, nothing to close

    ok = [r for r in rows if r["status"] == "ok" and r.get("level", 0) >= 1]
    F = np.array([[r[k] for k in objectives] for r in ok], dtype=float)
    lo, hi = F.min(axis=0), F.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    worst = np.where([DESIGN_METRICS[k].better == "max" for k in objectives], lo, hi)
    Z = np.abs(F - worst) / span  # 0 worst, 1 best
    fig = Figure(figsize=(2.1 * len(objectives) + 2.5, 5.0))
    ax = fig.subplots()
    col = {a: c for a, c in _colours(ok).items()}
    xs = np.arange(len(objectives))
    for z, r in zip(Z, ok):
        if r["level"] != 1 and r["kind"] != "reference":
            ax.plot(xs, z, color="0.82", lw=0.7, zorder=1)
    seen = set()
    for z, r in zip(Z, ok):
        if r["kind"] == "reference":
            ax.plot(xs, z, color="k", lw=2.0, ls="--", zorder=4, label=r["name"])
        elif r["level"] == 1:
            a = r["architecture"]
            ls = "-" if _vehicle(r) == "Q" else "-." if _vehicle(r) == "HEX" else ":"
            ax.plot(xs, z, color=col[_arm(r)], ls=ls, lw=1.6, zorder=3, label=None if a in seen else a)
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
