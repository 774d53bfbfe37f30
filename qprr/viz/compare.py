"""Figures that put several runs side by side (the comparisons of Thesis Chapter 6: Figs. 6.19-6.21 and the like).

Generic: each function takes ``{label: SimResult}`` (any platform, any controllers) and writes one
figure file; plotting stays out of the simulator, figures are pyplot-free ``matplotlib`` Figures
(:func:`qprr.viz.new_figure`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from ..charts import wrap_angle
from ..errors import InputError
from ..sim import SimResult
from .plots import coordinate_kinds, figure_path, new_figure, plain

_UNITS = {"length": "m", "angle": "rad", "unknown": "m or rad"}

ANGLES = (3, 4, 5)


def _errors(res: SimResult) -> np.ndarray:
    e = res.xi_d - res.xi
    e[:, ANGLES] = wrap_angle(e[:, ANGLES])
    return e


def _check(results: Mapping[str, SimResult]) -> None:
    if not results or any(not isinstance(r, SimResult) for r in results.values()):
        raise InputError("results must be a non-empty mapping label -> SimResult")


def plot_overlay(
    results: Mapping[str, SimResult], path, *, rows: Sequence[str] = ("position", "position error", "arm error"), title: str = "", time_window=None
) -> Path:
    """One row per entry of ``rows`` (3 columns each), every run overlaid (Figs. 6.19-6.21).

    ``rows``: "position" (x, y, z with the reference dashed, Fig. 6.19), "position error" (x_d - x ..., Fig. 6.20),
    "attitude" (phi, theta, psi), "arm" (the arm joints with references), "arm error" (Fig. 6.21), "thrust"
    (sum of the rotor thrusts, min and max rotor thrust). ``time_window`` (t0, t1) [s] limits the x axis.
    """
    _check(results)
    first = next(iter(results.values()))
    names = [plain(n) for n in first.names]
    units = [_UNITS[k] for k in coordinate_kinds(first)]
    n_arm = first.n_arm
    fig = new_figure((15, 3.2 * len(rows) + 0.6))
    axes = np.atleast_2d(fig.subplots(len(rows), 3, sharex=True, squeeze=False))
    for r, row in enumerate(rows):
        ax = axes[r]
        if row in ("position", "attitude", "arm"):
            idx = {"position": (0, 1, 2), "attitude": (3, 4, 5), "arm": tuple(range(6, 6 + min(3, n_arm)))}[row]
            for j, i in enumerate(idx):
                for k, (label, res) in enumerate(results.items()):
                    ax[j].plot(res.t, res.xi[:, i], color=f"C{k}", lw=1.1, label=label)
                ax[j].plot(first.t, first.xi_d[:, i], "k--", lw=0.8, label="reference")
                ax[j].set_ylabel(f"{names[i]} [{units[i]}]")
        elif row in ("position error", "arm error", "attitude error"):
            idx = {"position error": (0, 1, 2), "attitude error": (3, 4, 5), "arm error": tuple(range(6, 6 + min(3, n_arm)))}[row]
            for j, i in enumerate(idx):
                for k, (label, res) in enumerate(results.items()):
                    ax[j].plot(res.t, _errors(res)[:, i], color=f"C{k}", lw=1.0, label=label)
                ax[j].set_ylabel(f"{names[i]}_d - {names[i]} [{units[i]}]")
        elif row == "thrust":
            for k, (label, res) in enumerate(results.items()):
                ax[0].plot(res.t, res.f.sum(axis=1), color=f"C{k}", lw=1.0, label=label)
                ax[1].plot(res.t, res.f.max(axis=1), color=f"C{k}", lw=1.0, label=label)
                ax[2].plot(res.t, res.f.min(axis=1), color=f"C{k}", lw=1.0, label=label)
            ax[0].set_ylabel("total thrust [N]")
            ax[1].set_ylabel("largest rotor thrust [N]")
            ax[2].set_ylabel("smallest rotor thrust [N]")
        else:
            raise InputError(f"unknown overlay row {row!r}")
        for a in ax:
            a.grid(alpha=0.3)
            if time_window is not None:
                a.set_xlim(*time_window)
        handles, labels = ax[0].get_legend_handles_labels()  # right of the row: never over the curves
        ax[-1].legend(handles, labels, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    for a in axes[-1]:
        a.set_xlabel("t [s]")
    if title:
        fig.suptitle(title, fontsize=10)
    path = figure_path(path)
    fig.savefig(path, dpi=80)
    return path


def plot_rmse_bars(table: Mapping[str, Mapping[str, float]], path, *, title: str = "", log: bool = True) -> Path:
    """Grouped bars of RMSE per variable (rows of ``table``: label -> {variable: value}), log scale by default."""
    if not table:
        raise InputError("table must be a non-empty mapping")
    labels = list(table)
    variables = list(next(iter(table.values())))
    x = np.arange(len(variables))
    width = 0.8 / len(labels)
    fig = new_figure((max(8, 1.1 * len(variables) + 4), 4.2))
    ax = fig.subplots()
    for k, label in enumerate(labels):
        vals = [max(table[label].get(v, np.nan), 1e-12) for v in variables]
        ax.bar(x + (k - (len(labels) - 1) / 2) * width, vals, width, label=label, color=f"C{k}")
    ax.set_xticks(x, variables)
    if log:
        ax.set_yscale("log")
    ax.set_ylabel("RMSE (6.26) [m or rad]")
    ax.grid(alpha=0.3, axis="y")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    if title:
        ax.set_title(title, fontsize=10)
    path = figure_path(path)
    fig.savefig(path, dpi=80)
    return path


__all__ = ["plot_overlay", "plot_rmse_bars"]
