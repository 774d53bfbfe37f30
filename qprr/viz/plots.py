"""Figures of a simulation, panel by panel, in the style of the thesis's Chapter 6 (matplotlib Figures, no pyplot).

:func:`plot_result` draws any choice of panels of a :class:`qprr.sim.SimResult`, either on a new
page (saved to a file, or returned as a ``matplotlib.figure.Figure``) or into Axes you pass
(one panel per Axes), so that each thesis figure can be reproduced on its own::

    plot_result(res, "out/run.png")                              # the default page
    plot_result(res, "out/x.png", panels=("position", "cog"))     # two panels
    fig = plot_result(res, panels="path")                         # a Figure, not saved
    plot_result(res, panels="cog", ax=my_axes)                    # into your own Axes

Panels (:data:`PANELS`): ``position`` (B vs its reference, Fig. 6.7), ``attitude`` (roll/pitch
references from (6.17), Fig. 6.8), ``arm`` (joints, Fig. 6.9), ``errors_position`` and
``errors_angle`` (reference - measured, Fig. 6.10, 6.18), ``thrust`` (u_fb, world axes, Fig.
6.11), ``torques`` (u_tau, Fig. 6.12), ``arm_efforts`` (u_mu, Fig. 6.12), ``rotors`` (thrusts and
their bounds), ``path`` (3-D, Fig. 6.13-6.14), ``cog`` (x_cm, y_cm in B, Fig. 6.42-6.43) and
``disturbance`` (u_ext of (6.27)-(6.28)) and ``wind`` (the air the base flew in, world axes, when the run had a
wind: ``result.series["wind_velocity"]``).  The forces are the applied ones, S^T N f (what the
rotors and joints produced after the allocation); where the controller asked for something else (a
bound was active, or a force the rotors cannot produce), the commanded value is drawn dotted.  Your own panels are :class:`Panel` objects.

One style for every figure of the project: SI units on every axis, angles in radians (as on the
command line and in the thesis coordinates), the prismatic joints in metres (millimetres when
small) and the revolute ones in radians (two labelled axes when an arm has both, the lengths drawn
above the angles), labels built from the platform's own joint names and types (prismatic: m, N;
revolute: rad, N m; any name renders: mathtext specials are escaped), legends outside the data
(below each time panel), page titles wrapped to the page width, references dashed in black *above* the measured curves, axis limits that ignore spikes
of a few milliseconds (a clipped spike is marked by a red triangle at the edge, with its peak in
the legend), and a 3-D path with equal axes (millimetres about the start point when the motion
is small).  Figure numbers in the titles come from the scenario that made the result
(:attr:`qprr.scenarios.Scenario.figures`): a custom run carries none.

Plotting stays out of the simulator: it reads a :class:`~qprr.sim.SimResult`.  The library never
selects a matplotlib backend and never imports pyplot.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..actuation import AllocationFlag
from ..charts import euler_to_rotation_batch, force_to_xi_batch
from ..errors import InputError, MissingDependencyError, UnknownNameError
from ..registry import SCENARIOS
from ..sim import SimResult
from ..sim.result import RUN_FIGURES
from ..validation import as_int, as_settings, as_vector

DEG = 180.0 / math.pi
"""Degrees per radian (for figures that choose degrees explicitly; the panels here draw radians)."""
REFERENCE_STYLE = {"color": "k", "ls": (0, (4, 2)), "lw": 0.9, "zorder": 4}
"""References: thin black dashes drawn above the measured curves."""
COMMANDED_STYLE = {"ls": ":", "lw": 1.0, "zorder": 3}
ROBUST_FRACTION = 0.002
"""Axis limits span the [0.2 %, 99.8 %] quantiles of the data (plus a margin): a spike shorter than
0.2 % of the run (60 ms of a 30 s run) does not set the scale; it is marked where it is clipped."""
SMALL_PATH = 0.05
"""[m] below this extent the 3-D path is drawn in millimetres about its start point."""


# ============================================================================ files, figures
def new_figure(figsize=(16, 12)):
    """A matplotlib Figure not attached to pyplot (saved with ``fig.savefig``; no display, no backend choice)."""
    w, h = as_vector(figsize, 2, "figsize").tolist()
    if not (w > 0 and h > 0):
        raise InputError(f"figsize must be (width, height) > 0 in inches, got {(w, h)!r}")
    figsize = (w, h)
    try:
        from matplotlib.figure import Figure
    except ModuleNotFoundError as exc:  # pragma: no cover - runtime dependency
        if exc.name != "matplotlib":
            raise
        raise MissingDependencyError("matplotlib", "figures", "pip install matplotlib") from exc
    return Figure(figsize=figsize, layout="constrained")


def figure_path(path: str | Path) -> Path:
    """``path`` as a figure path (.png, .pdf, .svg) whose folder exists (a missing folder is an error naming it, not created)."""
    if not isinstance(path, (str, Path)) or str(path) == "":
        raise InputError(f"path must be a figure file path (.png, .pdf or .svg), got {path!r}")
    path = Path(path)
    if path.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise InputError(f"figure files end in .png, .pdf or .svg, got {str(path)!r}")
    if not path.parent.is_dir():
        raise InputError(f"cannot write {str(path)!r}: folder {str(path.parent)!r} does not exist")
    return path


def save_figure(fig, path: str | Path, dpi: int = 90) -> Path:
    """Save ``fig`` to ``path`` (checked by :func:`figure_path`) and return the path."""
    path = figure_path(path)
    fig.savefig(path, dpi=dpi)
    return path


# ============================================================================ labels and units
_GREEK = {"phi", "theta", "psi", "alpha", "beta", "gamma", "delta", "eta", "mu", "tau", "omega", "rho", "sigma", "chi", "zeta"}


def plain(text: str) -> str:
    """``text`` shown as it is written: every ``$`` escaped, so that matplotlib never parses it as mathtext
    (a URDF joint name such as ``j$1`` or ``a_b^c`` renders literally)."""
    return str(text).replace("$", "\\$")


def _symbol(name: str) -> str | None:
    """The mathtext body of a short coordinate name (``theta2`` -> ``\\theta_{2}``), None for any other name."""
    m = re.fullmatch(r"([A-Za-z]+)_?(\d*)", name)
    if m is None:
        return None
    base, sub = m.groups()
    if base in _GREEK:
        base = "\\" + base
    elif len(base) > 1:
        return None  # a long name (a URDF joint): not a symbol
    return f"{base}_{{{sub}}}" if sub else base


def pretty(name: str) -> str:
    """A coordinate name as a label: ``theta2`` -> $\\theta_2$, ``r0`` -> $r_0$, ``phi`` -> $\\phi$, ``x`` -> $x$;
    any other name (a URDF joint: ``shoulder``, ``j_1$``) as plain text (:func:`plain`)."""
    sym = _symbol(str(name))
    return plain(name) if sym is None else f"${sym}$"


def effort_label(name: str) -> str:
    """The generalised force of a joint: $u_{\\mu,\\theta_2}$ for a short name, $u_\\mu$ (shoulder) for any other."""
    sym = _symbol(str(name))
    return f"$u_{{\\mu,{sym}}}$" if sym is not None else f"$u_\\mu$ ({plain(name)})"


def _check_res(res) -> SimResult:
    """``res`` if it is a :class:`~qprr.sim.SimResult`, else an :class:`InputError` naming it."""
    if not isinstance(res, SimResult):
        raise InputError(f"res must be a qprr SimResult (qprr.sim.simulate, SimResult.load), got {type(res).__name__}")
    return res


def coordinate_kinds(res: SimResult) -> tuple[str, ...]:
    """Kind of each entry of xi: "length" (x, y, z, prismatic joints), "angle" (Euler angles, revolute joints) or "unknown"."""
    _check_res(res)
    kinds = ["length"] * 3 + ["angle"] * 3
    arm = res.arm_kinds
    for k in range(res.n_arm):
        kind = arm[k] if k < len(arm) else ""
        kinds.append("length" if kind == "prismatic" else "angle" if kind == "revolute" else "unknown")
    return tuple(kinds)


_UNIT = {"length": ("m", 1.0), "angle": ("rad", 1.0), "unknown": ("m or rad", 1.0)}
_FORCE_UNIT = {"length": "N", "angle": "N m", "unknown": "N or N m"}


# ============================================================================ style helpers
def time_axis(ax, res: SimResult) -> None:
    """The common time axis: label, limits of the run, light grid."""
    ax.set_xlabel("t [s]")
    if res.n > 1:
        ax.set_xlim(float(res.t[0]), float(res.t[-1]))
    ax.grid(alpha=0.3)


def robust_limits(
    ax, arrays: Sequence[np.ndarray], *, min_span: float, t=None, fraction: float = ROBUST_FRACTION, mark: bool = True
) -> tuple[float, float]:
    """Set the y limits of ``ax`` from the quantiles of ``arrays`` so that short spikes do not set the scale.

    The limits span the [``fraction``, 1 - ``fraction``] quantiles of all values, widened by 8 %
    and to at least ``min_span`` (a flat curve stays flat instead of showing rounding noise).
    Values outside are clipped by the axes; with ``mark`` and ``t`` their peaks are marked by red
    triangles at the edge.  Returns the limits.
    """
    vals = [np.asarray(a, dtype=float) for a in arrays if a is not None and np.size(a)]
    flat = np.concatenate([v.ravel() for v in vals]) if vals else np.zeros(1)
    flat = flat[np.isfinite(flat)]
    if flat.size == 0:
        flat = np.zeros(1)
    lo, hi = np.quantile(flat, [fraction, 1.0 - fraction]) if flat.size > 50 else (flat.min(), flat.max())
    true_lo, true_hi = float(flat.min()), float(flat.max())
    span = hi - lo
    pad = 0.08 * span
    lo, hi = lo - pad, hi + pad
    # keep what is barely outside the quantile range: only clip real outliers (> 25 % of the span beyond)
    if true_hi <= hi + 0.25 * max(span, min_span):
        hi = max(hi, true_hi + pad)
    if true_lo >= lo - 0.25 * max(span, min_span):
        lo = min(lo, true_lo - pad)
    if hi - lo < min_span:
        mid = 0.5 * (hi + lo)
        lo, hi = mid - 0.5 * min_span, mid + 0.5 * min_span
    ax.set_ylim(lo, hi)
    if mark and t is not None:
        clipped = []
        for v in vals:
            v2 = v.reshape(v.shape[0], -1) if v.ndim > 1 else v[:, None]
            for col in v2.T:
                for side, bad in (("top", col > hi), ("bottom", col < lo)):
                    if bad.any():
                        clipped.append((side, np.asarray(t)[bad], col[bad]))
        if clipped:
            peak = 0.0
            for side, tt, vv in clipped:
                y = hi if side == "top" else lo
                ax.plot(tt, np.full(tt.shape, y), "v" if side == "top" else "^", color="tab:red", ms=5, clip_on=False, zorder=5)
                peak = max(peak, float(np.max(np.abs(vv))))
            ax.plot([], [], "v", color="tab:red", ms=5, label=f"clipped spike (peak |{peak:.3g}|)")
    return lo, hi


LEGEND_DROP = 34.0
"""[points] the legend of a time panel hangs this far below the bottom of its axes: under the tick
labels and the "t [s]" label, outside the data (constrained layout makes room for it)."""


def legend(ax, *others, **kwargs) -> None:
    """One legend for ``ax`` and its twin axes ``others``, below the axes (outside the data), small font.

    ``kwargs`` go to ``Axes.legend`` (``loc`` and ``bbox_to_anchor`` place it elsewhere)."""
    from matplotlib.transforms import ScaledTranslation

    handles, labels = [], []
    for a in (ax, *others):
        for h, lab in zip(*a.get_legend_handles_labels()):
            if lab not in labels:  # one entry per label (host and twin may both explain their dotted commands)
                handles.append(h)
                labels.append(lab)
    if handles:
        drop = ScaledTranslation(0.0, -LEGEND_DROP / 72.0, ax.figure.dpi_scale_trans)
        opts = {
            "fontsize": 7.5,
            "framealpha": 0.85,
            "loc": "upper center",
            "bbox_to_anchor": (0.5, 0.0),
            "bbox_transform": ax.transAxes + drop,
            "handlelength": 1.8,
            "borderaxespad": 0.0,
            "columnspacing": 1.2,
        }
        opts.update(kwargs)
        if "ncol" not in opts:  # as many columns (at most 4) as the panel's column of the page holds
            opts["ncol"] = legend_columns(ax, labels, opts["fontsize"], opts["handlelength"], opts["columnspacing"])
        top = max((ax, *others), key=lambda a: a.get_zorder())  # drawn last: nothing covers its legend
        leg = top.legend(handles, labels, **opts)
        leg.set_zorder(10)


def legend_columns(ax, labels: Sequence[str], fontsize: float, handlelength: float, columnspacing: float, most: int = 4) -> int:
    """The most columns (1 to ``most``) in which a legend of ``labels`` under ``ax`` is no wider than the column of the
    page's grid that ``ax`` spans (the whole figure for axes outside a grid).  Widths in points: each entry's handle
    (``handlelength`` em), the gap to its text (0.8 em, matplotlib's default) and its text as rendered at ``fontsize``;
    columns filled as matplotlib fills them (the first ones one entry longer); the gaps between columns and the frame's
    padding (0.4 em per side); 90 % of the column, the legend being centred under its axes, not on the column.  A
    legend of long names (URDF joints, rotors) then wraps instead of running into its neighbours or off the page."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextToPath

    spec = ax.get_subplotspec()
    share = 1.0 if spec is None else len(spec.colspan) / spec.get_gridspec().ncols
    room = 0.9 * 72.0 * ax.figure.get_figwidth() * share  # centred under its axes, which sit off the column's centre
    measure, prop = TextToPath(), FontProperties(size=fontsize)
    widths = [measure.get_text_width_height_descent(lab, prop, ismath=lab.replace("\\$", "").count("$") >= 2)[0] for lab in labels]
    entry = [(handlelength + 0.8) * fontsize + w for w in widths]
    for k in range(min(most, len(labels)), 1, -1):
        rows = -(-len(labels) // k)
        sizes = [rows] * (k - (k * rows - len(labels))) + [rows - 1] * (k * rows - len(labels))
        starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        total = sum(max(entry[i : i + n]) for i, n in zip(starts, sizes) if n) + (k - 1) * columnspacing * fontsize + 0.8 * fontsize
        if total <= room:
            return k
    return 1


def _under(host, twin) -> None:
    """Draw ``twin`` (the angles) beneath ``host`` (the lengths): the host's curves stay visible where they cross."""
    host.set_zorder(twin.get_zorder() + 1)
    host.patch.set_visible(False)


def _draw_signals(ax, t, values, labels, *, colors, commanded=None, lw=1.4):
    """Measured curves (solid, colored) and, where ``commanded[k]`` is not None, the commanded ones (dotted, same color)."""
    for k, (y, lab) in enumerate(zip(values, labels)):
        ax.plot(t, y, color=colors[k], lw=lw, label=lab, zorder=2)
        if commanded is not None and commanded[k] is not None:
            ax.plot(t, commanded[k], color=colors[k], **COMMANDED_STYLE)


def _draw_references(ax, t, refs, label) -> None:
    """References (black dashed, on top of the curves); the first one carries ``label`` (None: no legend entry)."""
    for r in refs:
        ax.plot(t, r, label=label, **REFERENCE_STYLE)
        label = None


def length_unit(arrays) -> tuple[str, float]:
    """("mm", 1e3) when every value is below 0.1 m in magnitude, else ("m", 1)."""
    peak = max((float(np.max(np.abs(a))) for a in arrays if a is not None and np.size(a)), default=0.0)
    return ("mm", 1e3) if peak < 0.1 else ("m", 1.0)


def _coordinate_panel(ax, res, idx, *, what: str, errors: bool = False) -> None:
    """Coordinates ``idx`` of xi (measured vs reference, or reference - measured): lengths on the left axis
    (m, or mm when small), angles in radians (on a labelled twin axis when both kinds are present, drawn
    beneath the lengths so that neither group hides the other)."""
    t = res.t
    kinds = coordinate_kinds(res)
    lengths = [i for i in idx if kinds[i] != "angle"]
    angles = [i for i in idx if kinds[i] == "angle"]
    groups = [g for g in (lengths, angles) if g]
    two = len(groups) == 2
    colors = {i: f"C{k}" for k, i in enumerate(idx)}
    axes = []
    ref_label = "reference"
    for g, group in enumerate(groups):
        a = ax if g == 0 else ax.twinx()
        if g:
            _under(ax, a)
        kind = kinds[group[0]]
        if errors:
            e = res.xi_d[:, group] - res.xi[:, group]
            if kind == "angle":
                e = (e + math.pi) % (2 * math.pi) - math.pi
            raw, raw_refs = [e[:, j] for j in range(len(group))], []
        else:
            raw, raw_refs = [res.xi[:, i] for i in group], [res.xi_d[:, i] for i in group]
        if kind == "angle":
            unit, scale = "rad", 1.0
        elif kind == "length":
            unit, scale = length_unit(raw + raw_refs)
        else:
            unit, scale = "m or rad", 1.0
        vals, refs = [scale * v for v in raw], [scale * r for r in raw_refs]
        tag = f" [{unit}]" if two else ""
        _draw_signals(
            a,
            t,
            vals,
            [pretty(res.names[i]) + tag for i in group],
            colors=[colors[i] for i in group],
            lw=1.1 if errors else 1.4,
        )
        _draw_references(a, t, refs, ref_label)
        ref_label = None if refs else ref_label
        if errors:
            a.axhline(0.0, color="0.4", lw=0.6, zorder=1)
        if two:
            a.set_ylabel(f"{'lengths' if g == 0 else 'angles'}{' (ref. - meas.)' if errors else ''} [{unit}]")
        else:
            a.set_ylabel(f"{what} [{unit}]")
        if errors:  # errors: down to a micrometre or twenty microradians
            span = {"rad": 2e-5, "mm": 1e-3}.get(unit, 1e-6)
        else:  # values: a flat curve shows as flat, not as rounding noise
            span = {"rad": 0.02, "mm": 1.0, "m": 0.01}.get(unit, 1e-3)
        robust_limits(a, vals + refs, min_span=span, t=t)
        axes.append(a)
    time_axis(ax, res)
    legend(ax, *axes[1:])


def applied_forces(res: SimResult) -> np.ndarray:
    """u applied = S^T N f (thesis coordinates, (m, n_xi)): the controller's u minus what the allocation could not produce."""
    _check_res(res)
    R = euler_to_rotation_batch(res.xi[:, 3:6])
    return res.u - force_to_xi_batch(R, res.xi, res.unallocated)


def _force_panel(ax, res, idx, ylabel: str, labels) -> None:
    """Applied generalised forces ``idx`` (commanded dotted where they differ), forces left, torques on a twin axis."""
    t = res.t
    u_app = applied_forces(res)
    kinds = coordinate_kinds(res)
    by_unit = {}
    for i in idx:
        unit = "N" if i < 3 else "N m" if i < 6 else _FORCE_UNIT[kinds[i]]
        by_unit.setdefault(unit, []).append(i)
    groups = list(by_unit.items())
    colors = {i: f"C{k}" for k, i in enumerate(idx)}
    axes = []
    for g, (unit, group) in enumerate(groups[:2]):
        a = ax if g == 0 else ax.twinx()
        if g:
            _under(ax, a)
        vals = [u_app[:, i] for i in group]
        gap = [np.max(np.abs(res.u[:, i] - u_app[:, i])) if res.n else 0.0 for i in group]
        scale = max([np.max(np.abs(v)) for v in vals] + [1e-9])
        commanded = [res.u[:, i] if d > 0.005 * scale else None for i, d in zip(group, gap)]  # visible gaps only
        _draw_signals(
            a,
            t,
            vals,
            [labels[i] + (f" [{unit}]" if len(groups) > 1 else "") for i in group],
            colors=[colors[i] for i in group],
            commanded=commanded,
            lw=1.2,
        )
        if any(c is not None for c in commanded):
            a.plot([], [], color="0.3", label="commanded (where not produced)", **COMMANDED_STYLE)
        a.set_ylabel(f"{ylabel} [{unit}]" if len(groups) == 1 else f"{'forces' if unit == 'N' else 'torques'} [{unit}]")
        robust_limits(a, vals, min_span=1e-3, t=t)
        axes.append(a)
    time_axis(ax, res)
    legend(ax, *axes[1:])


def _u_labels(res: SimResult) -> list[str]:
    out = [r"$u_{f_b,x}$", r"$u_{f_b,y}$", r"$u_{f_b,z}$", r"$u_{\tau,\phi}$", r"$u_{\tau,\theta}$", r"$u_{\tau,\psi}$"]
    return out + [effort_label(n) for n in res.names[6:]]


# ============================================================================ the panels
@dataclass(frozen=True)
class Panel:
    """One panel: ``title`` (without figure number), ``draw(ax, res)``, ``projection`` ("3d" or None).

    ``name`` is the key of :attr:`qprr.scenarios.Scenario.figures` giving its figure number.  ``thesis_title``: the
    title of a run reproducing a thesis section (:func:`scenario_source`), which may cite the thesis's equations; any
    other run (a generic scenario, a user's platform) shows ``title`` (default: ``title`` for both).
    """

    name: str
    title: str
    draw: Callable
    projection: str | None = None
    thesis_title: str = ""

    def title_for(self, thesis: bool) -> str:
        """The panel's title for a run that reproduces a thesis section (``thesis``) or not."""
        return self.thesis_title if (thesis and self.thesis_title) else self.title


def _position(ax, res):
    _coordinate_panel(ax, res, [0, 1, 2], what="position of B")


def _attitude(ax, res):
    _coordinate_panel(ax, res, [3, 4, 5], what="attitude")


def _arm(ax, res):
    _coordinate_panel(ax, res, list(range(6, 6 + res.n_arm)), what="arm joints")


def _errors_position(ax, res):
    kinds = coordinate_kinds(res)
    _coordinate_panel(ax, res, [i for i in range(res.xi.shape[1]) if kinds[i] != "angle"], what="reference - measured", errors=True)


def _errors_angle(ax, res):
    kinds = coordinate_kinds(res)
    _coordinate_panel(ax, res, [i for i in range(res.xi.shape[1]) if kinds[i] == "angle"], what="reference - measured", errors=True)


def _thrust(ax, res):
    _force_panel(ax, res, [0, 1, 2], "thrust force, world axes", _u_labels(res))


def _torques(ax, res):
    _force_panel(ax, res, [3, 4, 5], "Euler torques", _u_labels(res))


def _arm_efforts(ax, res):
    _force_panel(ax, res, list(range(6, 6 + res.n_arm)), "arm efforts", _u_labels(res))


def _rotors(ax, res, thrust_bounds=None):
    t = res.t
    nr = res.f.shape[1]
    cols = [f"C{i % 10}" for i in range(nr)]
    _draw_signals(ax, t, [res.f[:, i] for i in range(nr)], rotor_labels(res), colors=cols, lw=1.1)
    sat = (res.flags & AllocationFlag.ROTOR_SATURATED) != 0
    lo, hi = robust_limits(ax, [res.f], min_span=0.1, t=t)
    if thrust_bounds is None and res.rotor_bounds is not None:  # the bounds the run's allocation respected
        thrust_bounds = tuple(float(b) for b in np.unique(res.rotor_bounds))
    if thrust_bounds:
        shown = [b for b in thrust_bounds if lo <= b <= hi]
        for b in shown:
            ax.axhline(b, color="0.3", ls=":", lw=1.0, zorder=1)
        off = [f"{b:g}" for b in thrust_bounds if b not in shown]
        ax.plot([], [], color="0.3", ls=":", lw=1.0, label="bounds" + (f" ({', '.join(off)} N: off scale)" if off else ""))
    if sat.any():
        ax.plot(t[sat], np.full(int(sat.sum()), hi), "|", color="tab:red", ms=6, clip_on=False, label="a bound active")
    ax.set_ylabel("rotor thrust [N]")
    time_axis(ax, res)
    legend(ax)


def rotor_labels(res: SimResult) -> list[str]:
    """One legend label per rotor of ``res``: the names its platform's rotor description gives (``res.rotor_names``,
    written as they are: mathtext specials escaped), or $f_1$ ... $f_n$ for a result that did not record them."""
    _check_res(res)
    if res.rotor_names:
        return [plain(name) for name in res.rotor_names]
    return [f"$f_{{{i + 1}}}$" for i in range(res.f.shape[1])]


def _cog(ax, res):
    t = res.t
    vals = [1e3 * res.x_cm[:, 0], 1e3 * res.x_cm[:, 1]]
    _draw_signals(ax, t, vals, [r"$x_{cm}$", r"$y_{cm}$"], colors=["C0", "C1"])
    ax.axhline(0.0, color="0.4", lw=0.6, zorder=1)
    robust_limits(ax, vals, min_span=0.1, t=t)
    ax.set_ylabel("CoG offset in B [mm]")
    time_axis(ax, res)
    legend(ax)


def _disturbance(ax, res):
    """u_ext, forces [N] left, torques [N m] on a twin axis; white noise (a new value every step) is shown
    over its first 0.05 s, where its samples can be seen (over the whole run it fills the panel)."""
    idx = [i for i in range(res.u_ext.shape[1]) if np.any(res.u_ext[:, i] != 0.0)] or [0, 1, 2]
    t = res.t
    u = res.u_ext
    changes = np.mean(np.diff(u[:, idx], axis=0) != 0.0) if res.n > 1 else 0.0
    window = changes > 0.5  # changes at most steps: noise
    sel = t <= t[0] + 0.05 if window else slice(None)
    kinds = coordinate_kinds(res)
    by_unit = {}
    for i in idx:
        by_unit.setdefault(("N" if i < 3 else "N m") if i < 6 else _FORCE_UNIT[kinds[i]], []).append(i)
    axes = []
    groups = list(by_unit.items())[:2]
    for g, (unit, group) in enumerate(groups):
        a = ax if g == 0 else ax.twinx()
        if g:
            _under(ax, a)
        for i in group:
            a.step(
                t[sel],
                u[sel, i],
                where="post",
                color=f"C{idx.index(i) % 10}",
                lw=0.9,
                label=f"{pretty(res.names[i])}" + (f" [{unit}]" if len(groups) > 1 else ""),
            )
        a.set_ylabel(f"{'forces' if unit == 'N' else 'torques' if unit == 'N m' else 'disturbance'} [{unit}]")
        robust_limits(a, [u[sel][:, group]], min_span=1e-3, mark=False)
        axes.append(a)
    time_axis(ax, res)
    if window:
        ax.set_xlim(float(t[0]), float(t[sel][-1]))
        ax.set_xlabel("t [s] (first 0.05 s: a new value every step)")
    legend(ax, *axes[1:])


WIND_SERIES = "wind_velocity"
"""The series of a run holding the wind it flew in, (m, 3) [m/s] world axes (the drag's report, :mod:`qprr.sim.wind`)."""


def _wind(ax, res):
    """The wind w(t) the base flew in [m/s], world axes (its x, y, z components and its speed |w|)."""
    w = np.asarray(res.series[WIND_SERIES], dtype=float)
    t = res.t[: w.shape[0]]
    speed = np.linalg.norm(w, axis=1)
    _draw_signals(ax, t, [w[:, 0], w[:, 1], w[:, 2]], ["$w_x$", "$w_y$", "$w_z$"], colors=["C0", "C1", "C2"], lw=1.1)
    ax.plot(t, speed, color="0.7", lw=3.0, label="$|w|$", zorder=1)  # wide and pale, under the components it often meets
    ax.axhline(0.0, color="0.4", lw=0.6, zorder=1)
    robust_limits(ax, [w[:, 0], w[:, 1], w[:, 2], speed], min_span=0.1, t=t)
    ax.set_ylabel("wind velocity, world axes [m/s]")
    time_axis(ax, res)
    legend(ax)


def _path(ax, res):
    p, pd = res.xi[:, 0:3], res.xi_d[:, 0:3]
    both = np.vstack([p, pd])
    lo, hi = both.min(axis=0), both.max(axis=0)
    extent = float(np.max(hi - lo))
    if extent < SMALL_PATH:
        origin, scale, unit = p[0].copy(), 1e3, "mm"
    else:
        origin, scale, unit = np.zeros(3), 1.0, "m"
    P, Pd = scale * (p - origin), scale * (pd - origin)
    ax.plot(P[:, 0], P[:, 1], P[:, 2], color="C0", lw=1.6, label="flown", zorder=2)
    ax.plot(Pd[:, 0], Pd[:, 1], Pd[:, 2], label="reference", **REFERENCE_STYLE)
    ax.scatter(*P[0], color="C2", s=18, label="start", depthshade=False)
    ax.scatter(*P[-1], color="C3", s=18, label="end", depthshade=False)
    allp = np.vstack([P, Pd])
    mid = 0.5 * (allp.min(axis=0) + allp.max(axis=0))
    half = 0.5 * max(float(np.max(allp.max(axis=0) - allp.min(axis=0))), 1e-3 if unit == "mm" else 1e-3)
    half *= 1.05
    for setter, m in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), mid):
        setter(m - half, m + half)
    ax.set_box_aspect((1, 1, 1), zoom=0.85)  # room for the axis labels inside the panel
    if unit == "mm":
        ax.set_xlabel("x - x0 [mm]")
        ax.set_ylabel("y - y0 [mm]")
        ax.set_zlabel("z - z0 [mm]")
        ax.text2D(
            1.0,
            1.0,
            f"about the start\n(x0, y0, z0) =\n({origin[0]:.3f}, {origin[1]:.3f}, {origin[2]:.3f}) m",
            transform=ax.transAxes,
            fontsize=7.5,
            ha="right",
            va="top",
        )
    else:
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.set_zlabel("z [m]")
    tidy_3d(ax)
    ax.legend(fontsize=7.5, loc="upper right", bbox_to_anchor=(0.0, 1.0), framealpha=0.85, borderaxespad=0.0)


def tidy_3d(ax, nbins: int = 4) -> None:
    """3-D axes whose tick labels do not run into each other: at most ``nbins`` ticks per axis, no offset, small font."""
    from matplotlib.ticker import MaxNLocator

    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(nbins))
        axis.get_major_formatter().set_useOffset(False)
    ax.tick_params(labelsize=7)


PANELS: dict[str, Panel] = {
    "position": Panel("position", "position of B", _position),
    "attitude": Panel(
        "attitude", "attitude (roll, pitch references from the controller)", _attitude, thesis_title="attitude (roll, pitch references from (6.17))"
    ),
    "arm": Panel("arm", "arm joints", _arm),
    "errors_position": Panel("errors_position", "tracking errors, lengths", _errors_position),
    "errors_angle": Panel("errors_angle", "tracking errors, angles", _errors_angle),
    "thrust": Panel("thrust", "thrust force $u_{f_b}$", _thrust),
    "torques": Panel("torques", r"torques $u_\tau$", _torques),
    "arm_efforts": Panel("arm_efforts", r"arm efforts $u_\mu$", _arm_efforts),
    "rotors": Panel("rotors", "rotor thrusts (allocation)", _rotors),
    "path": Panel("path", "3-D path of B", _path, "3d"),
    "cog": Panel("cog", "CoG offset in B", _cog),
    "disturbance": Panel("disturbance", "disturbance $u_{ext}$", _disturbance),
    "wind": Panel("wind", "wind the base flew in", _wind),
}
"""Every panel by name (see the module docstring)."""

DEFAULT_PANELS = (
    "position",
    "attitude",
    "arm",
    "errors_position",
    "errors_angle",
    "thrust",
    "torques",
    "arm_efforts",
    "rotors",
    "path",
    "cog",
    "disturbance",
)
"""The panels of the full page (``disturbance`` only when the run had one; ``wind`` added after them when the run had a
wind)."""


def _panel(spec) -> Panel:
    if isinstance(spec, Panel):
        return spec
    if isinstance(spec, str):
        if spec not in PANELS:
            raise UnknownNameError("panel", spec, tuple(PANELS))
        return PANELS[spec]
    raise InputError(f"a panel is a name ({', '.join(PANELS)}) or a qprr.viz.plots.Panel, got {spec!r}")


def scenario_figures(res: SimResult) -> dict[str, str]:
    """Figure numbers per panel of the scenario that made ``res`` (:attr:`Scenario.figures`; {} for a custom run).

    Read from the scenario registry (:data:`qprr.registry.SCENARIOS`), which this module reads without
    importing :mod:`qprr.scenarios` (that module runs plots: importing it here would close a cycle)."""
    _check_res(res)
    if res.scenario not in SCENARIOS:
        return {}
    return dict(SCENARIOS[res.scenario].figures)


def scenario_source(res: SimResult) -> str:
    """The thesis section a scenario's result reproduces ("" for a custom run; :func:`scenario_figures`)."""
    _check_res(res)
    return SCENARIOS[res.scenario].source if res.scenario in SCENARIOS else ""


def _title(panel: Panel, figures: Mapping[str, str], thesis: bool) -> str:
    fig = figures.get(panel.name)
    title = panel.title_for(thesis)
    return f"{title} (Fig. {fig})" if fig else title


def _events(ax, events, label: bool) -> None:
    """Vertical dash-dot lines at the event times; with ``label``, their names written at the top of ``ax``."""
    from matplotlib.transforms import blended_transform_factory

    tr = blended_transform_factory(ax.transData, ax.transAxes)
    for te, name in events:
        ax.axvline(te, color="0.35", lw=0.8, ls="-.", zorder=1)
        if label:
            ax.text(te, 0.98, f" {name}", transform=tr, fontsize=7.5, color="0.25", rotation=90, va="top", ha="right")


@dataclass(frozen=True)
class PlotOptions:
    """The page of :func:`plot_result` beyond its panels (each field also a keyword of :func:`plot_result`).

    title : page title (default: scenario, controller, status, thesis section and RMSE, :func:`default_title`).
    figures : figure numbers per panel name (default: those of the scenario that made the result; pass
        ``{}`` for none).
    thrust_bounds : thrust bounds [N] drawn on the ``rotors`` panel (default: the distinct values of the
        result's ``rotor_bounds``; none for a result that does not record them).
    events : (time [s], label) pairs drawn as vertical lines on the time panels (a release, a contact).
    ncols : columns of the page (default 3, or fewer panels).  dpi : of the saved file.
    """

    title: str | None = None
    figures: Mapping[str, str] | None = None
    thrust_bounds: tuple[float, ...] | None = None
    events: Sequence[tuple[float, str]] = ()
    ncols: int | None = None
    dpi: int = 90

    def __post_init__(self) -> None:  # checked however the options are built
        object.__setattr__(self, "dpi", as_int(self.dpi, "dpi", lo=1))
        if self.ncols is not None:
            object.__setattr__(self, "ncols", as_int(self.ncols, "ncols", lo=1))
        if self.figures is not None and not isinstance(self.figures, Mapping):
            raise InputError(f"figures must be a mapping panel name -> figure number (or None), got {self.figures!r:.80}")
        if self.title is not None and not isinstance(self.title, str):
            raise InputError(f"title must be a string (or None), got {self.title!r:.80}")
        try:
            events = tuple((float(te), str(name)) for te, name in self.events)
        except (TypeError, ValueError):
            raise InputError(f"events must be (time [s], label) pairs, got {self.events!r:.80}") from None
        if not all(math.isfinite(te) for te, _ in events):
            raise InputError(f"events must have finite times, got {self.events!r:.80}")
        object.__setattr__(self, "events", events)


def plot_result(res: SimResult, path: str | Path | None = None, *, panels=None, ax=None, options: PlotOptions | None = None, **settings):
    """Draw ``panels`` of ``res``; save to ``path`` (.png, .pdf, .svg) or return the Figure, or draw into ``ax``.

    Parameters
    ----------
    res : a :class:`~qprr.sim.SimResult`.
    path : file to write (its folder must exist); None: return the ``matplotlib.figure.Figure``.
    panels : a panel name, a :class:`Panel`, or a sequence of them (default :data:`DEFAULT_PANELS`).
    ax : an Axes (one panel) or a sequence of Axes (one per panel) to draw into; the panels are then
        drawn on your figure and nothing is saved (``path`` must be None).  The ``path`` panel needs
        an Axes with ``projection="3d"``.
    options : a :class:`PlotOptions` (title, figure numbers, thrust bounds, events, columns, dpi), and/or its fields
        as keywords, which replace the options' (``plot_result(res, "run.png", thrust_bounds=(0.5, 15.0))``).

    Returns
    -------
    The ``path`` when given; with ``ax``, the Axes' Figure; else a new Figure.
    """
    o = as_settings(options, PlotOptions, "options", **settings)
    _check_res(res)
    chosen = _chosen_panels(res, panels)
    figures = scenario_figures(res) if o.figures is None else dict(o.figures)
    draw = _PanelDrawer(res, figures, o.thrust_bounds, o.events)
    if ax is not None:
        if path is not None:
            raise InputError("plot_result: give either ax (draw into your Axes) or path (save a new figure), not both")
        return _draw_into(ax, chosen, draw)
    fig = _page(chosen, draw, o.ncols)
    title = default_title(res) if o.title is None else o.title
    if title:  # wrapped to the page: a single panel's page is narrower than the RMSE line
        n = len(chosen)
        fig.suptitle(wrap_title(title, fig.get_figwidth(), 10.5 if n > 1 else 9), fontsize=10.5 if n > 1 else 9)
    if path is None:
        return fig
    return save_figure(fig, path, o.dpi)


RUN_FIGURES.register(RUN_FIGURES.default, plot_result)  # SimResult.plot() (its entry point names it too)


def _chosen_panels(res: SimResult, panels) -> list[Panel]:
    """The panels to draw: ``panels`` (a name, a :class:`Panel` or a sequence of them), default :data:`DEFAULT_PANELS`
    without the disturbance panel of a run that has none, with the wind panel of a run that recorded its wind; a wind
    panel asked for a run that recorded none is refused."""
    explicit = panels is not None
    if panels is None:
        panels = DEFAULT_PANELS
    specs = [panels] if isinstance(panels, (str, Panel)) else list(panels)
    if not specs:
        raise InputError("panels must name at least one panel")
    chosen = [_panel(s) for s in specs]
    if explicit:
        if WIND_SERIES not in res.series and any(p.draw is _wind for p in chosen):
            raise InputError(f"panel 'wind': run {res.scenario!r} recorded no wind (no series {WIND_SERIES!r}: it flew in still air)")
        return chosen
    if not np.any(res.u_ext):
        chosen = [p for p in chosen if p.name != "disturbance"]
    return chosen + ([PANELS["wind"]] if WIND_SERIES in res.series else [])


class _PanelDrawer:
    """Draws one panel of ``res`` into an Axes: its curves, its title (with the thesis figure number) and the event
    lines (their names written on the first time panel only)."""

    def __init__(self, res: SimResult, figures: Mapping[str, str], thrust_bounds, events: tuple) -> None:
        self.res, self.figures, self.thrust_bounds, self.events = res, figures, thrust_bounds, events
        self.thesis = bool(scenario_source(res))  # a run reproducing a thesis section: its titles may cite equations
        self.labelled: list[str] = []

    def __call__(self, p: Panel, a) -> None:
        if p.name == "rotors" and p.draw is _rotors:
            _rotors(a, self.res, self.thrust_bounds)
        else:
            p.draw(a, self.res)
        a.set_title(_title(p, self.figures, self.thesis), fontsize=10)
        if self.events and p.projection is None:
            _events(a, self.events, label=not self.labelled)
            self.labelled.append(p.name)


def _draw_into(ax, chosen: list[Panel], draw: _PanelDrawer):
    """The panels drawn into the caller's Axes (one per panel; 3-D panels need 3-D Axes); returns their Figure."""
    from matplotlib.axes import Axes

    axes = list(ax) if isinstance(ax, (list, tuple, np.ndarray)) else [ax]
    axes = list(np.ravel(axes))
    if len(axes) != len(chosen):
        raise InputError(f"plot_result: {len(chosen)} panel(s) for {len(axes)} Axes")
    for p, a in zip(chosen, axes):
        if not isinstance(a, Axes):
            raise InputError(f"plot_result: ax must be a matplotlib Axes or a sequence of them, got {type(a).__name__}")
        if (p.projection == "3d") != (a.name == "3d"):
            need = "an Axes with projection='3d'" if p.projection == "3d" else "a 2-D Axes"
            raise InputError(f"panel {p.name!r} needs {need}")
        draw(p, a)
    return axes[0].figure


def _page(chosen: list[Panel], draw: _PanelDrawer, ncols: int | None):
    """A new Figure with the panels on a grid of ``ncols`` columns (default 3, or fewer panels)."""
    n = len(chosen)
    ncols = min(3, n) if ncols is None else int(ncols)
    if ncols < 1:
        raise InputError(f"ncols must be >= 1, got {ncols!r}")
    nrows = math.ceil(n / ncols)
    fig = new_figure((5.4 * ncols, 3.7 * nrows + (0.6 if n > 1 else 0.3)))
    for k, p in enumerate(chosen):
        a = fig.add_subplot(nrows, ncols, k + 1, projection=p.projection)
        draw(p, a)
    return fig


def wrap_title(title: str, width_in: float, fontsize: float) -> str:
    """``title`` with each line broken after ", " so that it fits ``width_in`` inches at ``fontsize`` points
    (a character of the default sans-serif font is at most about 0.62 em wide)."""
    import textwrap

    chars = max(20, int(0.95 * width_in * 72.0 / (0.62 * fontsize)))
    return "\n".join(textwrap.fill(line, chars, break_long_words=False, break_on_hyphens=False) for line in title.split("\n"))


def _wrap_at(text: str, chars: int) -> str:
    """``text`` with each line broken at spaces to at most ``chars`` characters, a word longer than that broken after
    its underscores (``rmse_shoulder_pitch_joint``), never inside a run of letters."""
    import re
    import textwrap

    out = []
    for line in text.split("\n"):
        for piece in textwrap.wrap(line, chars, break_long_words=False, break_on_hyphens=False) or [""]:
            cur = ""
            for token in re.split(r"(?<=_)", piece):
                if cur and len(cur) + len(token) > chars:
                    out.append(cur)
                    cur = ""
                cur += token
            out.append(cur)
    return "\n".join(out)


def fit_texts(fig, rounds: int = 3) -> None:
    """Re-wrap the titles, axis labels and figure texts of ``fig`` that leave the page, measured on the rendered page.

    A centred text (title, axis label, suptitle) is wrapped to twice the room from its centre to the nearer page edge
    (vertical for a rotated label); its layout is drawn again and checked, at most ``rounds`` times."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    texts = list(fig.texts)
    for a in fig.axes:
        texts += [a.title, a.xaxis.label, a.yaxis.label]
    texts = [t for t in texts if t.get_text() and "$" not in t.get_text()]  # mathtext is never broken apart
    original = {id(t): t.get_text() for t in texts}
    for _ in range(rounds):
        canvas.draw()
        renderer, page = canvas.get_renderer(), fig.bbox
        moved = False
        for t in texts:
            bb = t.get_window_extent(renderer)
            vertical = abs(t.get_rotation() % 180 - 90) < 1.0
            lo, hi, page_lo, page_hi = (bb.y0, bb.y1, page.y0, page.y1) if vertical else (bb.x0, bb.x1, page.x0, page.x1)
            if lo >= page_lo - 0.5 and hi <= page_hi + 0.5:
                continue
            centre = 0.5 * (lo + hi)
            room = 2.0 * min(centre - page_lo, page_hi - centre)
            longest = max(len(line) for line in t.get_text().split("\n"))
            chars = max(8, int(0.95 * longest * room / (hi - lo)))
            if chars >= longest:
                chars = longest - 1
            t.set_text(_wrap_at(original[id(t)], chars))
            moved = True
        if not moved:
            return


def default_title(res: SimResult) -> str:
    """Scenario / controller (status), the thesis section it reproduces, and the RMSE with units (angles in radians, as
    on the command line), "RMSE (6.26)" for a run that reproduces a thesis section (equation numbers only there)."""
    _check_res(res)
    src = scenario_source(res)
    on = f" on {res.platform}" if res.platform else ""
    head = f"{res.scenario} / {res.controller}{on} ({res.status}, {res.n} steps of {1e3 * res.control_period:g} ms)"
    if src:
        head += f" - thesis {src}"
    kinds = coordinate_kinds(res)
    parts = []
    for (name, v), kind in zip(res.rmse().items(), kinds):
        unit, scale = _UNIT[kind]
        parts.append(f"{plain(name)} {scale * v:.2g} {unit}")
    return head + ("\nRMSE (6.26): " if src else "\nRMSE: ") + ", ".join(parts)


__all__ = [
    "DEFAULT_PANELS",
    "PANELS",
    "Panel",
    "applied_forces",
    "coordinate_kinds",
    "default_title",
    "effort_label",
    "figure_path",
    "fit_texts",
    "legend",
    "legend_columns",
    "new_figure",
    "plain",
    "plot_result",
    "pretty",
    "robust_limits",
    "rotor_labels",
    "save_figure",
    "scenario_figures",
    "tidy_3d",
    "time_axis",
    "wrap_title",
]
