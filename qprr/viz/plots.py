"""Figures of a simulation, laid out like the thesis's Chapter 6 plots (matplotlib, PNG files).

:func:`plot_result` draws one 3 x 3 page: positions of B vs desired (Fig. 6.7), attitude vs
the (6.17) references (Fig. 6.8), arm joints (Fig. 6.9), tracking errors (Fig. 6.10, 6.18),
u_fb (Fig. 6.11), u_tau and u_mu (Fig. 6.12), rotor thrusts with their bounds, the 3-D path
(Fig. 6.13, 6.14) and the CoG offset in B (Fig. 6.42-6.43).  Plotting stays out of the
simulator: it reads a :class:`qprr.sim.SimResult`.  Figures are ``matplotlib.figure.Figure``
objects saved directly (no pyplot, no backend selected: the library never calls
``matplotlib.use``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..charts import as_vector
from ..errors import InputError, MissingDependencyError
from ..sim import SimResult


def new_figure(figsize=(16, 12)):
    """A matplotlib Figure not attached to pyplot (saved with ``fig.savefig``; no display, no backend choice)."""
    w, h = as_vector(figsize, 2, "figsize").tolist()
    if not (w > 0 and h > 0):
        raise InputError(f"figsize must be (width, height) > 0 in inches, got {(w, h)!r}")
    figsize = (w, h)
    try:
        from matplotlib.figure import Figure
    except ImportError as exc:  # pragma: no cover - runtime dependency
        raise MissingDependencyError("matplotlib", "figures", "pip install matplotlib") from exc
    return Figure(figsize=figsize)


def figure_path(path: str | Path) -> Path:
    """``path`` as a PNG path whose folder exists (a missing folder is an error naming it, not created)."""
    if not isinstance(path, (str, Path)) or str(path) == "":
        raise InputError(f"path must be a figure file path (.png, .pdf or .svg), got {path!r}")
    path = Path(path)
    if path.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise InputError(f"figure files end in .png, .pdf or .svg, got {str(path)!r}")
    if not path.parent.is_dir():
        raise InputError(f"cannot write {str(path)!r}: folder {str(path.parent)!r} does not exist")
    return path


def plot_result(res: SimResult, path: str | Path, *, title: str | None = None, thrust_bounds=None) -> Path:
    """Save a 3 x 3 figure of ``res`` to ``path`` (PNG) and return the path.  ``thrust_bounds`` (f_min, f_max) [N] drawn dotted."""
    if not isinstance(res, SimResult):
        raise InputError(f"res must be a qprr.sim.SimResult, got {type(res).__name__}")
    path = figure_path(path)
    names = res.names
    t = res.t
    fig = new_figure((16, 12))
    colors = ("tab:blue", "tab:orange", "tab:green")

    def tracks(ax, idx, ylabel, scale=1.0):
        for c, i in zip(colors, idx):
            ax.plot(t, scale * res.xi[:, i], color=c, label=names[i])
            ax.plot(t, scale * res.xi_d[:, i], color=c, ls="--", lw=1, label=f"{names[i]} desired")
        ax.set_ylabel(ylabel)
        ax.legend(fontsize=7, ncol=2)
        ax.grid(alpha=0.3)

    ax = fig.add_subplot(3, 3, 1)
    tracks(ax, (0, 1, 2), "position of B [m]")
    ax.set_title("positions (Fig. 6.7)")
    ax = fig.add_subplot(3, 3, 2)
    tracks(ax, (3, 4, 5), "attitude [deg]", 180 / np.pi)
    ax.set_title("attitude; roll/pitch references from (6.17)")
    ax = fig.add_subplot(3, 3, 3)
    for k in range(res.n_arm):
        i = 6 + k
        ax.plot(t, res.xi[:, i], color=f"C{k}", label=names[i])
        ax.plot(t, res.xi_d[:, i], color=f"C{k}", ls="--", lw=1)
    ax.set_ylabel("arm joints [m or rad]")
    ax.set_title("arm joints (Fig. 6.9), dashed: desired")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)

    ax = fig.add_subplot(3, 3, 4)
    e = np.abs(res.xi_d - res.xi)
    for i, name in enumerate(names):
        ax.semilogy(t, np.maximum(e[:, i], 1e-12), lw=0.8, label=name)
    ax.set_ylim(1e-9, None)
    ax.set_ylabel("|error| [m, rad]")
    ax.set_title("tracking errors (Fig. 6.10, 6.18)")
    ax.legend(fontsize=6, ncol=3)
    ax.grid(alpha=0.3)
    ax = fig.add_subplot(3, 3, 5)
    for c, i, lab in zip(colors, (0, 1, 2), ("u_fb,x", "u_fb,y", "u_fb,z")):
        ax.plot(t, res.u[:, i], color=c, label=lab)
    ax.set_ylabel("[N]")
    ax.set_title("thrust vector u_fb (Fig. 6.11)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax = fig.add_subplot(3, 3, 6)
    for i in range(3, len(names)):
        lab = f"u_tau,{names[i]}" if i < 6 else f"u_mu,{names[i]}"
        ax.plot(t, res.u[:, i], lw=0.9, label=lab)
    ax.set_ylabel("[N m, N]")
    ax.set_title("u_tau and u_mu (Fig. 6.12)")
    ax.legend(fontsize=6, ncol=2)
    ax.grid(alpha=0.3)

    ax = fig.add_subplot(3, 3, 7)
    for i in range(res.f.shape[1]):
        ax.plot(t, res.f[:, i], lw=0.9, label=f"f{i + 1}")
    for b in thrust_bounds or ():
        ax.axhline(b, color="k", ls=":", lw=0.8)
    sat = (res.flags & 1) != 0
    if sat.any():
        ax.plot(t[sat], np.full(sat.sum(), float(res.f.max())), "r|", ms=4, label="saturated")
    ax.set_ylabel("rotor thrust [N]")
    ax.set_title("rotor thrusts (allocation, bounds dotted)")
    ax.legend(fontsize=7, ncol=3)
    ax.grid(alpha=0.3)
    ax = fig.add_subplot(3, 3, 8, projection="3d")
    ax.plot(res.xi[:, 0], res.xi[:, 1], res.xi[:, 2], label="flown")
    ax.plot(res.xi_d[:, 0], res.xi_d[:, 1], res.xi_d[:, 2], ls="--", lw=1, label="desired")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_title("3-D path (Fig. 6.13)")
    ax.legend(fontsize=7)
    ax = fig.add_subplot(3, 3, 9)
    ax.plot(t, 1e3 * res.x_cm[:, 0], label="x_cm")
    ax.plot(t, 1e3 * res.x_cm[:, 1], label="y_cm")
    ax.set_ylabel("CoG offset in B [mm]")
    ax.set_xlabel("t [s]")
    ax.set_title("x_cm (Fig. 6.42-6.43)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    for k in (1, 2, 3, 4, 5, 6, 7):
        fig.axes[k - 1].set_xlabel("t [s]")
    rmse = res.rmse()
    sub = ", ".join(f"{k} {v:.1e}" for k, v in rmse.items())
    fig.suptitle((title or f"{res.scenario} / {res.controller} ({res.status}): {res.n} steps in {res.wall_time:.2f} s")
                 + f"\nRMSE (6.26): {sub}", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    fig.savefig(path, dpi=90)
    return path
