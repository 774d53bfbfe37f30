"""Figures of the analysis maps (matplotlib; never imported by the maps themselves).

Every ``plot_*`` function draws into an ``ax`` (a new figure if None) and returns it; every
``*_figure`` function returns a complete :class:`matplotlib.figure.Figure`.  Save with
``fig.savefig(path)``.  The library never selects a matplotlib backend.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..viz.plots import legend, new_figure, plain, tidy_3d
from ._common import error_bar_text
from .capacity import LIMITS, CapacityResult
from .cog import CoGBalanceMap, CoGResult
from .hover import HoverResult
from .opspace import OpSpaceMap
from .singularity import SingularityResult
from .workspace import WorkspaceResult

AXIS = ("x", "y", "z")
COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple")


def _new_ax(ax, projection=None):
    if ax is not None:
        return ax
    fig = new_figure((6, 5))
    return fig.add_subplot(111, projection=projection)


def _axis_names(basis: np.ndarray) -> list[str]:
    out = []
    for b in basis:
        i = int(np.argmax(np.abs(b)))
        out.append(f"{AXIS[i]}_B [m]" if abs(abs(b[i]) - 1.0) < 1e-9 else "hull axis [m]")
    return out


def measure_text(m) -> str:
    """A length, area or volume with its error bar, as a reader writes it: ``0.2004 ± 0.0004 m²``
    (:func:`qprr.analysis._common.error_bar_text` of its ``measure``, ``error``, ``unit``)."""
    return error_bar_text(m.measure, m.error, m.unit)


def _legend_below(ax) -> None:
    """The legend under the axes (outside the regions it names)."""
    legend(ax, ncol=1)


def _cells_image(ax, grid, origin, h, colour, alpha, label=None):
    """Fill covered cells of a 2-D occupancy grid."""
    from matplotlib.colors import ListedColormap

    img = np.where(grid.T, 1.0, np.nan)
    extent = (origin[0], origin[0] + grid.shape[0] * h, origin[1], origin[1] + grid.shape[1] * h)
    ax.imshow(img, origin="lower", extent=extent, cmap=ListedColormap([colour]), alpha=alpha, interpolation="nearest")
    if label:
        ax.fill([], [], color=colour, alpha=alpha, label=label)


def _sample_cells(points: np.ndarray, free: np.ndarray | None = None):
    """(occupancy of the sample points ``points`` (n, 2) [m] on the finest cells they fill without pinholes or isolated
    cells (:func:`qprr.analysis.voxels.display_occupancy`), occupancy of the samples where ``free`` (n,) holds on the
    same cells (None without ``free`` or when it holds nowhere), origin [m], cell side [m])."""
    from .voxels import display_occupancy, occupancy

    occ, o, h = display_occupancy(points)
    focc = None
    if free is not None and np.any(free):
        focc, _ = occupancy(points[free], h, (points.min(axis=0), points.max(axis=0)))
    return occ, focc, o, h


def _free_label(measure) -> str:
    return f"collision-free: {measure_text(measure)}" if measure is not None else "collision-free (no cell with every corner free)"


# ================================================================================ workspace
def plot_workspace(result: WorkspaceResult, ax=None, regions=None, title: str | None = None, collision: bool = True):
    """Body-frame workspace regions (filled covered cells and outlines) in their hull's axes; with ``collision`` and a
    collision check, each region's collision-free part drawn over it (darker, with its measure)."""
    ax = _new_ax(ax)
    regions = range(len(result.regions)) if regions is None else regions
    for i in regions:
        r = result.regions[i]
        if r.occupancy is None or r.dim not in (2, 3):
            continue
        colour = COLOURS[i % len(COLOURS)]
        free = r.collision_free if collision else None
        label = f"{plain(r.label)}: {measure_text(r.measure)}" + (" (x-z projection)" if r.dim == 3 else "")
        if r.dim == 2 and free is None:  # hull coordinates shifted back to B's axes
            grid, o, h = r.outline if r.outline is not None else r.occupancy
            _cells_image(ax, grid, o + r.origin @ r.basis.T, h, colour, 0.35 if i == 0 else 0.55, label)
        else:  # from the samples: the plane's coordinates, or the x-z projection of a 3-D set
            pts = r.coords + r.origin @ r.basis.T if r.dim == 2 else r.points_body[:, [0, 2]]
            occ, focc, o, h = _sample_cells(pts, free)
            _cells_image(ax, occ, o, h, colour, 0.25 if free is not None else 0.45, label if free is None else f"all configurations, {label}")
            if focc is not None:
                _cells_image(ax, focc, o, h, colour, 0.75, _free_label(r.free_measure))
        if r.dim == 2:
            for ln in r.boundary:
                loc = ln @ r.basis.T
                ax.plot(loc[:, 0], loc[:, 1], color=colour, lw=0.8)
    r0 = result.regions[0]
    names = _axis_names(r0.basis) if r0.dim == 2 else ["x_B [m]", "z_B [m]"]
    ax.set_xlabel(names[0])
    ax.set_ylabel(names[1] if len(names) > 1 else "")
    ax.set_aspect("equal")
    _legend_below(ax)
    ax.set_title(title or f"workspace of {plain(result.frame)} in B", fontsize=10)
    return ax


def plot_hover_workspace(result: WorkspaceResult, ax=None, regions=None):
    """Hover workspace (yaw free about z_B): the section (s, z) of each region drawn from its profile's samples and
    their mirror image (s = signed distance to the axis), its collision-free part over it when checked."""
    ax = _new_ax(ax)
    regions = range(len(result.regions)) if regions is None else regions
    for i in regions:
        r = result.regions[i]
        if r.hover_occupancy is None:
            continue
        colour = COLOURS[i % len(COLOURS)]
        free = None if r.collision_free is None else np.concatenate([r.collision_free, r.collision_free])
        pts = np.vstack([r.profile, r.profile * np.array([-1.0, 1.0])])
        occ, focc, o, h = _sample_cells(pts, free)
        label = f"{plain(r.label)}: {measure_text(r.hover_volume)}"
        alpha = 0.25 if free is not None else (0.35 if i == 0 else 0.55)
        free_label = f"{plain(r.label)}, {_free_label(r.free_hover_volume)}"
        if r.hover_counted is not None and r.hover_counted[2] < h:  # the cells the volume counted are finer: those
            _half_and_mirror(ax, r.hover_counted, colour, alpha, label)
            if r.free_hover_counted is not None:
                _half_and_mirror(ax, r.free_hover_counted, colour, 0.75 if i == 0 else 0.9, free_label)
            continue
        _cells_image(ax, occ, o, h, colour, alpha, label)
        if focc is not None:
            _cells_image(ax, focc, o, h, colour, 0.75 if i == 0 else 0.9, free_label)
    ax.axvline(0.0, color="k", lw=0.6, ls="--")
    ax.set_xlabel("distance to the yaw axis (signed) [m]")
    ax.set_ylabel("z (world, from the base) [m]")
    ax.set_aspect("equal")
    _legend_below(ax)
    ax.set_title("hover workspace: section through the yaw axis", fontsize=10)
    return ax


def _half_and_mirror(ax, counted, colour, alpha, label) -> None:
    """The counted half section (s >= 0, :mod:`qprr.analysis.voxels`) and its mirror image s -> -s."""
    grid, o, h = counted
    _cells_image(ax, grid, o, h, colour, alpha, label)
    _cells_image(ax, grid[::-1], np.array([-(o[0] + grid.shape[0] * h), o[1]]), h, colour, alpha)


def plot_hover_solid(result: WorkspaceResult, ax=None, region: int = 0, n_turn: int = 60):
    """3-D view of the hover workspace of ``region``: its outline turned about z."""
    ax = _new_ax(ax, projection="3d")
    r = result.regions[region]
    if r.hover_occupancy is None:
        return ax
    # two free joints: the cells the volume counted (the half section s >= 0, what turns about z); more: the finer
    # section drawn from the samples
    grid, o, h = r.hover_counted if r.free_joints <= 2 else r.hover_occupancy
    import contourpy

    x = o[0] + (np.arange(grid.shape[0]) + 0.5) * h
    y = o[1] + (np.arange(grid.shape[1]) + 0.5) * h
    lines = contourpy.contour_generator(x, y, grid.T.astype(float)).lines(0.5)
    phi = np.linspace(0, 2 * np.pi, n_turn)
    for ln in lines:
        ln = np.asarray(ln)
        ln = ln[ln[:, 0] >= 0] if np.any(ln[:, 0] >= 0) else ln
        s, z = ln[:: max(1, len(ln) // 80), 0], ln[:: max(1, len(ln) // 80), 1]
        X = np.outer(np.abs(s), np.cos(phi))
        Y = np.outer(np.abs(s), np.sin(phi))
        Z = np.outer(z, np.ones_like(phi))
        ax.plot_surface(X, Y, Z, alpha=0.25, color=COLOURS[region % len(COLOURS)], linewidth=0)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.set_box_aspect(None, zoom=0.82)  # room for the z label and the tick labels inside the panel
    tidy_3d(ax)
    ax.set_title(f"hover workspace, {plain(r.label)}:\n{measure_text(r.hover_volume)}", fontsize=9)
    return ax


def workspace_figure(result: WorkspaceResult):
    """Thesis Fig. 3.14 (a) with / (b) without the locked joints, Fig. 3.15 the gain, and the hover views.

    With locked joints (the slider of the Q-PRR): two rows of three panels, the regions in B and
    their difference above, the hover section and both solids below.  Without (a platform with
    no prismatic joint: one region): one row, the region in B, its hover section and its solid.
    """
    n = len(result.regions)
    if n == 1:
        fig = new_figure((16, 6.4))  # room for two legend rows (a collision-free part) under the panels
        plot_workspace(result, fig.add_subplot(1, 3, 1), [0], title=f"(a) {result.regions[0].label}, in B")
        plot_hover_workspace(result, fig.add_subplot(1, 3, 2))
        plot_hover_solid(result, fig.add_subplot(1, 3, 3, projection="3d"), 0)
        fig.suptitle(f"{result.platform_name}: workspace (Thesis (3.1)-(3.3))")
        return fig
    fig = new_figure((14, 10))  # room for the legends' collision-free rows
    plot_workspace(result, fig.add_subplot(2, 3, 1), [0], title=f"(a) {result.regions[0].label}")
    plot_workspace(result, fig.add_subplot(2, 3, 2), [1], title=f"(b) {result.regions[1].label}")
    ax3 = fig.add_subplot(2, 3, 3)
    gained = "(c) gained by the free joints"
    if 1 in result.gain:  # the gain belongs to the panel's title, not to a note floating over the regions
        g, d = result.gain[1], result.difference[1]
        unit = measure_text(dataclasses.replace(result.regions[0].measure, measure=d[0], error=d[1]))
        gained += f":\nx{g.value:.3f} ± {g.error:.1g} (+ {unit})"
    plot_workspace(result, ax3, [0, 1], title=gained, collision=False)
    plot_hover_workspace(result, fig.add_subplot(2, 3, 4))
    plot_hover_solid(result, fig.add_subplot(2, 3, 5, projection="3d"), 0)
    plot_hover_solid(result, fig.add_subplot(2, 3, 6, projection="3d"), 1)
    fig.suptitle(f"{result.platform_name}: workspace (Thesis (3.1)-(3.3), Fig. 3.14/3.15)")
    return fig


# ================================================================================ CoG
def plot_cog_regions(result: CoGResult, ax=None, keys=None, title=None):
    """CoG regions in the (x, z) plane of B (Thesis Fig. 6.31/6.32, 6.47/6.48): the counted cells of a region in that
    plane, else the x-z projection of its samples on cells they fill."""
    ax = _new_ax(ax)
    keys = list(result.regions) if keys is None else keys
    keys = sorted(keys, key=lambda k: -result.regions[k].mass)  # heavier payloads (larger regions) underneath
    for c, key in enumerate(keys):
        r = result.regions[key]
        colour = COLOURS[c % len(COLOURS)]
        label = f"{plain(r.label)}, payload {r.mass:g} kg" + (f": {measure_text(r.measure)}" if r.measure is not None else "")
        if r.occupancy is not None and r.basis.shape[0] == 2 and np.allclose(np.abs(r.basis), np.eye(3)[[0, 2]]):
            grid, o, h = r.occupancy
            _cells_image(ax, grid, o + r.origin @ r.basis.T, h, colour, 0.4, label)
        else:
            occ, _, o, h = _sample_cells(r.com[:, [0, 2]])
            _cells_image(ax, occ, o, h, colour, 0.4, label + (" (x-z projection)" if r.basis.shape[0] == 3 else ""))
    ax.axvline(0.0, color="k", lw=0.6, ls="--", label="thrust axis")
    ax.set_xlabel("x_cm in B [m]")
    ax.set_ylabel("z_cm in B [m]")
    _legend_below(ax)
    ax.set_title(title or f"CoG regions of {result.platform_name}")
    return ax


def plot_balance(result: CoGBalanceMap, ax=None, axes=None):
    """Slider position r* that balances the CoG over two joints (NaN where none within the limits); without a slider,
    the smallest |CoG offset| per end-effector cell (the x-z projection of a 3-D workspace)."""
    ax = _new_ax(ax)
    g = result.grid
    if result.slider is None:
        coords, basis, h = _plane(result.ee_body)
        _workspace_map(ax, coords, result.offset_clamped, h, "coolwarm", "smallest |CoG offset| [m]", smallest=True)
        names = _axis_names(basis) if basis.shape[0] == 2 else ["x_B [m]", "z_B [m]"]
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
        ax.set_title("CoG offset from the thrust axis, best configuration per end-effector cell", fontsize=9)
        return ax
    free = [a for a in range(len(g.shape)) if g.shape[a] > 1]
    axes = axes or _two_longest(g, free)
    sl = _slice_index(g, axes)
    vals = np.where(result.balanced, result.r_star, np.nan).reshape(g.shape)[sl]
    a0, a1 = g.axes[axes[0]], g.axes[axes[1]]
    im = ax.pcolormesh(a0, a1, vals.T, shading="nearest", cmap="coolwarm")
    ax.figure.colorbar(im, ax=ax, label=f"r* of {result.slider} [m] (blank: not balanced)")
    ax.set_xlabel(g.label(axes[0]))
    ax.set_ylabel(g.label(axes[1]))
    ax.set_title(f"CoG on the thrust axis: {100 * result.fraction_configurations:.1f}% of the grid", fontsize=9)
    return ax


def plot_balanced_workspace(result: CoGBalanceMap, ax=None):
    """End-effector positions reachable with the CoG balanced (in the x-z plane of B)."""
    ax = _new_ax(ax)
    ok = result.balanced
    coords, basis, _ = _plane(result.ee_body)
    occ, focc, o, h = _sample_cells(coords[:, [0, 2]] if coords.shape[1] == 3 else coords, ok)
    label = "CoG balanced"
    if result.fraction_workspace is not None:
        label += f": {100 * result.fraction_workspace.value:.2f} ± {100 * result.fraction_workspace.error:.1g} % of the workspace"
    _cells_image(ax, occ, o, h, "0.6", 0.3, "workspace (slider at its balancing position, clamped)")
    if focc is not None:
        _cells_image(ax, focc, o, h, "tab:green", 0.8, label)
    names = _axis_names(basis) if basis.shape[0] == 2 else ["x_B [m]", "z_B [m]"]
    ax.set_xlabel(names[0])
    ax.set_ylabel(names[1])
    ax.set_aspect("equal")
    _legend_below(ax)
    ax.set_title("end-effector positions with the CoG on the thrust axis", fontsize=9)
    return ax


def _balanced_panel_note(balance: CoGBalanceMap) -> str:
    """Why the panel of balanced end-effector positions is left out ("" when it is drawn: the set has a measure)."""
    if balance.balanced_measure is not None:
        return ""
    what = (
        f"no slider: |CoG offset| <= {balance.tol:g} m holds on {100 * balance.fraction_configurations:.2g} % of the grid only, "
        "a set without area or volume (the arm cannot move its CoG along the thrust axis at will)"
        if balance.slider is None
        else f"the balanced configurations cover no measurable set ({balance.reason})"
    )
    return f"balanced end-effector positions not drawn: {what}"


def cog_figure(result: CoGResult, balance: CoGBalanceMap | None = None):
    """CoG regions per variant and payload (Thesis Fig. 6.31/6.32/6.47/6.48) and the balance map; the panel of balanced
    end-effector positions only when that set has a measure (a note in the figure says why it is left out)."""
    nv = len(result.variants)
    note = _balanced_panel_note(balance) if balance is not None else ""
    nb = 0 if balance is None else (1 if note else 2)
    n = nv + nb
    ncol = n if n <= 3 else 2
    nrow = (n + ncol - 1) // ncol
    fig = new_figure((6.5 * ncol, 5.2 * nrow))
    for v in range(nv):
        keys = [k for k in result.regions if k[0] == v]
        plot_cog_regions(result, fig.add_subplot(nrow, ncol, v + 1), keys, title=f"CoG, {result.regions[keys[0]].label}")
    if balance is not None:
        plot_balance(balance, fig.add_subplot(nrow, ncol, nv + 1))
        if not note:
            plot_balanced_workspace(balance, fig.add_subplot(nrow, ncol, nv + 2))
    if note:  # a figure-level x label: the layout keeps room for it below the legends
        fig.supxlabel(note, fontsize=8)
    fig.suptitle(f"{result.platform_name}: CoG regions (Thesis (3.78), (6.29)-(6.33))")
    return fig


# ================================================================================ singularity
def _two_longest(g, free):
    order = sorted(free, key=lambda a: -len(g.axes[a]))
    return tuple(sorted(order[:2])) if len(order) >= 2 else (order[0], order[0])


def _slice_index(g, axes, at=None):
    idx = []
    for a in range(len(g.shape)):
        if a in axes:
            idx.append(slice(None))
        else:
            idx.append(len(g.axes[a]) // 2 if at is None or a not in at else int(np.argmin(np.abs(g.axes[a] - at[a]))))
    return tuple(idx)


def singularity_figure(result: SingularityResult, reference=None, system_axis=None):
    """(a) det J_t (or manipulability) over two joints with the singular set, (b) distance to it,
    (c) the system's det(J J^T) (the measure of Thesis (4.44)) against one joint at three values of
    another, with ``reference`` curves {label: (x, y)} (e.g. the printed (4.46)-(4.48) for the Q-PRR,
    :func:`qprr.analysis.cli.map_reference`) drawn dashed on top."""
    g = result.grid
    free = [a for a in range(len(g.shape)) if g.shape[a] > 1]
    axes = _two_longest(g, free)
    sl = _slice_index(g, axes)
    fig = new_figure((16, 4.6))
    axs = fig.subplots(1, 3)
    a0, a1 = g.axes[axes[0]], g.axes[axes[1]]
    others = ", ".join(f"{g.names[a]} = {g.axes[a][len(g.axes[a]) // 2]:.3g} {g.unit(a)}" for a in free if a not in axes)
    if result.det_task is not None:
        vals, label = result.det_task.reshape(g.shape)[sl], f"det J_t [m^{result.rank}]"
        lim = np.abs(vals).max()
        im = axs[0].pcolormesh(a0, a1, vals.T, shading="nearest", cmap="RdBu_r", vmin=-lim, vmax=lim)
        axs[0].contour(a0, a1, vals.T, levels=[0.0], colors="k", linewidths=1.2)
    else:
        vals, label = result.manipulability.reshape(g.shape)[sl], f"manipulability [m^{result.rank}]"
        im = axs[0].pcolormesh(a0, a1, vals.T, shading="nearest", cmap="viridis")
        S = result.singular.reshape(g.shape)[sl]
        if S.any():
            axs[0].contour(a0, a1, S.T.astype(float), levels=[0.5], colors="w", linewidths=1.0)
    fig.colorbar(im, ax=axs[0], label=label)
    axs[0].set_title(f"task {result.task} {list(result.rows)}" + (f" ({others})" if others else ""), fontsize=8)
    D = result.distance.reshape(g.shape)[sl]
    im = axs[1].pcolormesh(a0, a1, np.where(np.isfinite(D), D, np.nan).T, shading="nearest", cmap="magma")
    fig.colorbar(im, ax=axs[1], label="distance to the singular set [rad or m/L]")
    axs[1].set_title(f"distance to the singular set (L = {result.length:.3g} m)", fontsize=8)
    for ax in axs[:2]:
        ax.set_xlabel(g.label(axes[0]))
        ax.set_ylabel(g.label(axes[1]))
    # (c): det_system along one joint, at the first / middle / last value of another
    sa = system_axis if system_axis is not None else axes[0] if len(free) < 3 else free[1]
    va = next((a for a in free if a != sa), sa)
    for j, idx in enumerate((0, len(g.axes[va]) // 2, len(g.axes[va]) - 1)):
        s2 = _slice_index(g, (sa,), {va: g.axes[va][idx]})
        y = result.det_system.reshape(g.shape)[s2]
        axs[2].plot(g.axes[sa], y, color=COLOURS[j], lw=2.0, alpha=0.6, label=f"model, {g.names[va]} = {g.axes[va][idx]:.3g} {g.unit(va)}")
    for j, (lab, (x, y)) in enumerate((reference or {}).items()):
        axs[2].plot(x, y, color=COLOURS[j], ls="--", lw=1.0, label=lab)
    axs[2].set_xlabel(g.label(sa))
    axs[2].set_ylabel("det(J J^T), J = [base | arm] at zero Euler angles")
    _legend_below(axs[2])
    axs[2].set_title("the system's det(J J^T) (Thesis (4.44))" + (": never 0" if result.det_system.min() > 0 else ""), fontsize=8)
    fig.suptitle(f"{result.platform_name}: singularities (Thesis (4.42)-(4.45))")
    return fig


# ================================================================================ hover / capacity
def _workspace_map(ax, coords, values, h, cmap, label, smallest: bool = False):
    """The largest of ``values`` per cell of side ``h`` of the points ``coords`` (a 3-D map projected onto x-z first:
    the largest over y), coloured by ``cmap`` with a colour bar named ``label`` (none if empty); a field that is the same
    in every cell is drawn in one colour with its value in a legend entry (a colour bar over a constant reads as
    "no data"); returns the image.  ``h``: :func:`_plane`'s, no finer than the samples fill; ``smallest``: the smallest
    value per cell instead."""
    from ._common import best_per_cell

    pts = coords[:, [0, 2]] if coords.shape[1] == 3 else coords  # the projection of a 3-D set (affine_span: B's axes)
    sign = -1.0 if smallest else 1.0
    best, _, o = best_per_cell(pts, sign * np.asarray(values, dtype=float), h)
    best = sign * best
    extent = (o[0], o[0] + best.shape[0] * h, o[1], o[1] + best.shape[1] * h)
    finite = best[np.isfinite(best)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 0.0)
    if isinstance(cmap, str) and hi - lo <= 1e-9 * max(1.0, abs(hi)):
        from matplotlib.colors import ListedColormap

        im = ax.imshow(
            np.where(np.isfinite(best), 1.0, np.nan).T,
            origin="lower",
            extent=extent,
            cmap=ListedColormap(["tab:cyan"]),
            alpha=0.6,
            interpolation="nearest",
        )
        ax.fill([], [], color="tab:cyan", alpha=0.6, label=f"{label}: {hi:.4g} in every cell (constant)")
        _legend_below(ax)
    else:
        im = ax.imshow(best.T, origin="lower", extent=extent, cmap=cmap, interpolation="nearest")
        if label:
            ax.figure.colorbar(im, ax=ax, label=label)
    ax.set_aspect("equal")
    return im


def _yes_no_map(ax, coords, ok, h, yes: str, no: str) -> None:
    """Cells where ``ok`` holds for some sample (green) or for none (red), with a two-entry legend, not a colour bar."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    cmap = ListedColormap(["tab:red", "tab:green"])
    im = _workspace_map(ax, coords, ok.astype(float), h, cmap, "")
    im.set_norm(BoundaryNorm([-0.5, 0.5, 1.5], 2))
    cells = np.ma.filled(np.ma.asarray(im.get_array(), dtype=float), np.nan)
    share = float(np.nanmean(cells)) if np.isfinite(cells).any() else 0.0
    ax.fill([], [], color="tab:green", label=f"{yes} ({100 * share:.1f} % of the cells)")
    ax.fill([], [], color="tab:red", label=f"{no} ({100 * (1 - share):.1f} %)")
    _legend_below(ax)


def _plane(ee):
    """(the end-effector positions in their hull's axes, the hull's basis, the map's cell side [m]: 80 across or
    coarser, as the samples fill the cells of the drawn plane: the x-z projection of a 3-D set)."""
    from ._common import affine_span
    from .voxels import map_cell

    _, basis = affine_span(ee)
    coords = ee @ basis.T
    return coords, basis, map_cell(coords[:, [0, 2]] if coords.shape[1] == 3 else coords, 80)


def hover_figure(result: HoverResult, mass_index: int = 0):
    """Best thrust margin and attitude authority per workspace cell, infeasible cells, feasible share vs payload."""
    coords, basis, h = _plane(result.ee_body)
    names = _axis_names(basis) if basis.shape[0] == 2 else ["x_B [m]", "z_B [m]"]
    k = mass_index
    fig = new_figure((16, 9))
    axs = fig.subplots(2, 3)
    _workspace_map(axs[0, 0], coords, result.thrust_margin[k], h, "viridis", "best thrust margin [N]")
    axs[0, 0].set_title(f"thrust margin (payload {result.masses[k]:g} kg, best configuration per cell)", fontsize=8)
    for j, axis in enumerate(("roll", "pitch", "yaw")):
        ax = axs[0, 1] if j == 0 else axs[0, 2] if j == 1 else axs[1, 0]
        _workspace_map(ax, coords, result.authority[k, :, j], h, "cividis", f"{axis} authority left [N m]")
        ax.set_title(f"largest {axis} torque still available", fontsize=8)
    # the payload whose feasible share is nearest one half: the map with the most to say (all green or all red says
    # only what the envelope panel shows)
    kk = int(np.argmin(np.abs(result.feasible_fraction - 0.5)))
    _yes_no_map(axs[1, 1], coords, result.feasible[kk], h, "hover possible", "impossible")
    share = f"{100 * result.feasible_fraction[kk]:.1f} % of the configurations"
    axs[1, 1].set_title(f"where hovering is possible with {result.masses[kk]:g} kg ({share}; some configuration per cell)", fontsize=8)
    for ax in list(axs[0]) + [axs[1, 0], axs[1, 1]]:
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1] if len(names) > 1 else "")
    ax = axs[1, 2]
    ax.plot(result.masses, 100 * result.feasible_fraction, "o-", label="hover-feasible")
    ax.plot(result.masses, 100 * result.rotor_ok.mean(axis=1), "s--", label="rotors within bounds")
    ax.plot(result.masses, 100 * result.effort_ok.mean(axis=1), "^--", label="efforts within limits")
    ax.set_xlabel("payload [kg]")
    ax.set_ylabel("share of the configurations [%]")
    _legend_below(ax)
    ax.set_title(f"payload envelope; collective limit {result.payload.collective:.3g} kg", fontsize=8)
    fig.suptitle(f"{result.platform_name}: hover feasibility and thrust margin")
    return fig


def wrench_set_figure(result: HoverResult, index: int | None = None):
    """2-D sections of the rotors' wrench set through the hover wrench of one configuration (default: the worst)."""
    from scipy.spatial import HalfspaceIntersection, QhullError

    W = result.wrench_set
    i = int(np.argmin(result.thrust_margin[0])) if index is None else index
    w0 = result.hover_wrench[i]
    pairs = [(0, 1), (3, 4), (2, 5)] if W.rank == 6 else [(3, 4), (2, 5), (3, 5)]
    names = ("f_x [N]", "f_y [N]", "f_z [N]", "tau_x [N m]", "tau_y [N m]", "tau_z [N m]")
    fig = new_figure((5 * len(pairs), 4.5))
    axs = fig.subplots(1, len(pairs))
    for ax, (a, b) in zip(axs, pairs):
        E = np.zeros((2, 6))
        E[0, a] = E[1, b] = 1.0
        A = W.normals @ (E @ W.basis.T).T  # facets in the section coordinates (t_a, t_b)
        off = W.offsets - W.normals @ (W.basis @ w0)
        hs = np.column_stack([A, -off])
        try:
            poly = HalfspaceIntersection(hs, np.zeros(2)).intersections
        except QhullError:  # the hover point is not interior: nothing to draw
            continue
        ctr = poly.mean(axis=0)
        order = np.argsort(np.arctan2(poly[:, 1] - ctr[1], poly[:, 0] - ctr[0]))
        P = poly[order] + w0[[a, b]]
        ax.fill(P[:, 0], P[:, 1], alpha=0.3)
        ax.plot(*w0[[a, b]], "k+", ms=12, label="hover wrench")
        ax.set_xlabel(names[a])
        ax.set_ylabel(names[b])
        _legend_below(ax)
    q = result.grid.configurations(i, i + 1)[0]
    fig.suptitle(f"{result.platform_name}: wrench set (rank {W.rank}) sections at q_arm = {np.round(q, 3).tolist()}", fontsize=9)
    return fig


def capacity_figure(result: CapacityResult):
    """Thesis Fig. 6.46 generalised: best payload per workspace cell and the factor that limits it there.

    Drawn from the configurations (a 3-D workspace projected onto x-z first: the best over y), on cells the samples
    fill (:func:`_plane`); the shares in the legend are the result's, over its own cells
    (:meth:`~qprr.analysis.capacity.CapacityResult.map_fractions`)."""
    from matplotlib.colors import BoundaryNorm, ListedColormap

    from ._common import best_per_cell

    fig = new_figure((13, 5))
    axs = fig.subplots(1, 2)
    coords, basis, h = _plane(result.ee_body)
    pts = coords[:, [0, 2]] if coords.shape[1] == 3 else coords
    _workspace_map(axs[0], coords, result.capacity, h, "viridis", "largest payload [kg]")
    axs[0].set_title(f"payload capacity (reserve {np.round(result.torque_reserve, 3).tolist()} N m); collective {result.m_thrust:.3g} kg", fontsize=8)
    _, arg, o = best_per_cell(pts, np.where(result.limiting == 3, -1.0, result.capacity), h)
    lim = np.where(arg >= 0, result.limiting[np.clip(arg, 0, None)], -1).astype(float)
    lim[lim < 0] = np.nan
    extent = (o[0], o[0] + lim.shape[0] * h, o[1], o[1] + lim.shape[1] * h)
    cmap = ListedColormap(["tab:blue", "tab:orange", "tab:red", "0.3"])
    axs[1].imshow(lim.T, origin="lower", extent=extent, cmap=cmap, norm=BoundaryNorm([-0.5, 0.5, 1.5, 2.5, 3.5], 4), interpolation="nearest")
    fr = result.map_fractions()
    for k, name in enumerate(LIMITS):
        axs[1].fill([], [], color=cmap(k), label=f"{name} ({100 * fr[name]:.1f}% of the cells)")
    _legend_below(axs[1])
    axs[1].set_title("limiting factor (at the best configuration of each cell)", fontsize=8)
    names = _axis_names(basis) if basis.shape[0] == 2 else ["x_B [m]", "z_B [m]"]
    for ax in axs:
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1] if len(names) > 1 else "")
        ax.set_aspect("equal")
    fig.suptitle(f"{result.platform_name}: payload capacity over the workspace (Thesis Fig. 6.46 generalised)")
    return fig


def opspace_figure(result: OpSpaceMap):
    """Effective end-effector mass along x and z, and the conditioning of Lambda, over two joints (others at mid-range)."""
    g = result.grid
    free = [a for a in range(len(g.shape)) if g.shape[a] > 1]
    axes = _two_longest(g, free)
    sl = _slice_index(g, axes)
    a0, a1 = g.axes[axes[0]], g.axes[axes[1]]
    fig = new_figure((16, 4.6))
    axs = fig.subplots(1, 3)
    panels = [
        (result.mass_xyz[:, 0], "effective mass along x [kg]", "plasma"),
        (result.mass_xyz[:, 2], "effective mass along z [kg]", "plasma"),
        (np.log10(result.condition), "log10 cond(Lambda)", "viridis"),
    ]
    for ax, (vals, label, cmap) in zip(axs, panels):
        im = ax.pcolormesh(a0, a1, vals.reshape(g.shape)[sl].T, shading="nearest", cmap=cmap)
        fig.colorbar(im, ax=ax, label=label)
        ax.set_xlabel(g.label(axes[0]))
        ax.set_ylabel(g.label(axes[1]))
    others = ", ".join(f"{g.names[a]} = {g.axes[a][len(g.axes[a]) // 2]:.3g} {g.unit(a)}" for a in free if a not in axes)
    fig.suptitle(f"{result.platform_name}: operational-space inertia at the end effector (Thesis (5.47)-(5.52))" + (f", {others}" if others else ""))
    return fig
