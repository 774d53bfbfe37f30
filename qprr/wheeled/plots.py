"""Figures of wheeled robots: paths, robot outlines, wheel axes and ICR, wheel speeds.

Every function draws on a matplotlib ``Axes`` the caller owns (or, for the ``save_*``
helpers, writes a PNG to a path); nothing here is called by the models or the simulator,
and matplotlib is imported only by the functions that need it.  The library never selects
a matplotlib backend.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..charts import rot_z
from ..errors import InputError
from ..validation import as_int, as_vector
from ..viz.plots import figure_path, legend, new_figure
from .chassis import ICRStatus, WheeledRobot
from .kinematics import KinematicModel
from .sim import WheeledSimResult
from .wheels import WheelKind

COLORS = {WheelKind.FIXED: "k", WheelKind.CENTRED_STEERABLE: "tab:red", WheelKind.OFF_CENTRED_STEERABLE: "tab:gray", WheelKind.SWEDISH: "tab:blue"}


def _wheel_geometry(robot: WheeledRobot, sigma):
    """[(wheel, contact point (robot frame), rolling direction, axle direction)]."""
    angles = dict(zip((id(w) for w in robot.steered_wheels), robot.steering_angles(sigma))) if robot.n_steering else {}
    out = []
    for w in robot.wheels:
        s = angles.get(id(w), 0.0)
        a, d = w.directions(s)
        if w.kind is WheelKind.SWEDISH:  # draw the wheel's own plane, not the roller-turned one
            A = w.alpha + w.beta
            a, d = np.array([math.cos(A), math.sin(A)]), np.array([math.sin(A), -math.cos(A)])
        out.append((w, w.contact_point(s), d, a))
    return out


WHEEL_NAMES = {
    WheelKind.FIXED: "fixed wheel",
    WheelKind.CENTRED_STEERABLE: "centred steerable wheel",
    WheelKind.OFF_CENTRED_STEERABLE: "off-centred steerable wheel",
    WheelKind.SWEDISH: "Swedish wheel",
}
"""What each wheel colour of :data:`COLORS` means (the legend of :func:`wheel_legend`)."""
VISIBLE = 12.0
"""A path longer than this many robot sizes draws the robot enlarged (by a stated factor) so that it can be seen."""


def wheel_legend(ax, robot: WheeledRobot) -> None:
    """Legend entries (no drawing) naming the colour of each kind of wheel ``robot`` has."""
    for kind in dict.fromkeys(w.kind for w in robot.wheels):
        ax.plot([], [], color=COLORS[kind], lw=3, solid_capstyle="butt", label=WHEEL_NAMES[kind])


def robot_size(robot: WheeledRobot) -> float:
    """[m] the largest extent of the wheel contact points and O_R (at zero steering), at least 0.1 m."""
    pts = np.array([[0.0, 0.0]] + [g[1] for g in _wheel_geometry(robot, np.zeros(robot.n_steering))])
    return max(float(np.ptp(pts[:, 0])), float(np.ptp(pts[:, 1])), 0.1)


def draw_robot(
    ax, robot: WheeledRobot, pose=(0.0, 0.0, 0.0), sigma=None, *, color: str = "0.4", alpha: float = 1.0, scale: float = 1.0, label: str | None = None
) -> None:
    """Chassis outline (convex hull of the wheels and O_R) and wheels (segments along their
    planes, length 2 r) of ``robot`` at world ``pose`` = (x, y, theta) and steering ``sigma``,
    drawn ``scale`` times its size about the pose (``scale`` > 1 shows a robot on a long path)."""
    from matplotlib.patches import Polygon

    x, y, th = (float(v) for v in pose)
    R = scale * rot_z(th)[:2, :2]
    sig = np.zeros(robot.n_steering) if sigma is None else np.asarray(sigma, dtype=float)
    geo = _wheel_geometry(robot, sig)
    pts = np.array([[0.0, 0.0]] + [g[1] for g in geo])
    span = max(np.ptp(pts[:, 0]), np.ptp(pts[:, 1]), 0.1)
    hull = _hull(np.vstack([pts + span * 0.08 * np.array(c) for c in ((1, 1), (1, -1), (-1, 1), (-1, -1))]))
    world = hull @ R.T + [x, y]
    ax.add_patch(Polygon(world, closed=True, fill=True, fc=color, alpha=0.12 * alpha, lw=0, label=label))
    ax.add_patch(Polygon(world, closed=True, fill=False, ec=color, alpha=0.8 * alpha, lw=0.8))
    for w, p, d, _ in geo:
        c = (R @ p) + [x, y]
        dw = R @ d * w.r
        ax.plot([c[0] - dw[0], c[0] + dw[0]], [c[1] - dw[1], c[1] + dw[1]], color=COLORS[w.kind], lw=3, alpha=alpha, solid_capstyle="butt")
        if w.kind is WheelKind.OFF_CENTRED_STEERABLE:
            ax.plot(*c, "o", ms=3, color=COLORS[w.kind], alpha=alpha)
    h = R @ np.array([span * 0.25, 0.0])
    ax.annotate("", xy=(x + h[0], y + h[1]), xytext=(x, y), arrowprops={"arrowstyle": "->", "color": color, "alpha": alpha})


def _cross2(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def _hull(P: np.ndarray) -> np.ndarray:
    """Convex hull (monotone chain) of 2-D points."""
    P = np.unique(P.round(12), axis=0)
    if len(P) < 3:
        return P
    P = P[np.lexsort((P[:, 1], P[:, 0]))]

    def half(points):
        h = []
        for p in points:
            while len(h) >= 2 and _cross2(h[-1] - h[-2], p - h[-2]) <= 0:
                h.pop()
            h.append(p)
        return h

    lower, upper = half(P), half(P[::-1])
    return np.array(lower[:-1] + upper[:-1])


def plot_icr(ax, robot: WheeledRobot, sigma=None, twist=None, *, extent: float | None = None) -> None:
    """Robot at the origin, the axis of every fixed and centred steerable wheel (dashed) and the
    ICR: a point, a line (delta_m = 2) or a note when it is at infinity / anywhere.

    Lecture: "Centre instantané de rotation: le point où les prolongements des axes de rotation
    des roues se coupent"."""
    sig = np.zeros(robot.n_steering) if sigma is None else np.asarray(sigma, dtype=float)
    draw_robot(ax, robot, (0.0, 0.0, 0.0), sig)
    icr = robot.icr(sig, twist)
    pts = [g[1] for g in _wheel_geometry(robot, sig)]
    L = extent or 2.5 * max(0.5, max(np.linalg.norm(p) for p in pts))
    if icr.status is ICRStatus.UNIQUE:
        L = max(L, 1.3 * float(np.linalg.norm(icr.point_R)))
    for w, p, _, a in _wheel_geometry(robot, sig):
        if w.constrains_posture:
            ax.plot([p[0] - L * a[0], p[0] + L * a[0]], [p[1] - L * a[1], p[1] + L * a[1]], ls="--", lw=0.7, color=COLORS[w.kind])
    if icr.status is ICRStatus.UNIQUE:
        ax.plot(*icr.point_R, "*", ms=12, color="tab:green", label="ICR")
    elif icr.status is ICRStatus.LINE:
        p0, d = icr.point_R, icr.direction
        ax.plot([p0[0] - L * d[0], p0[0] + L * d[0]], [p0[1] - L * d[1], p0[1] + L * d[1]], color="tab:green", lw=2, alpha=0.5, label="ICR line")
    ax.set_title(f"{robot.name}: ICR {icr.status.value}", fontsize=9)
    ax.set_xlabel("x_R [m]")
    ax.set_ylabel("y_R [m]")
    ax.set_aspect("equal")
    ax.set_xlim(-L, L)
    ax.set_ylim(-L, L)
    ax.grid(alpha=0.3)


def plot_path(
    ax, result: WheeledSimResult, model: KinematicModel | None = None, *, n_robots: int = 6, color: str = "tab:blue", label: str | None = None
) -> None:
    """(x, y) path of ``result``; with ``model``, its robot drawn at ``n_robots`` instants (enlarged, with the
    factor in the legend, when the path is longer than :data:`VISIBLE` robot sizes) and a legend of its wheels."""
    q = result.q
    ax.plot(q[:, 0], q[:, 1], color=color, lw=1.2, label=label or result.model)
    ax.plot(q[0, 0], q[0, 1], "o", color=color, ms=4)
    ax.plot(q[-1, 0], q[-1, 1], "s", color=color, ms=4)
    if model is not None and model.robot is not None and n_robots > 0:
        size = robot_size(model.robot)
        extent = max(float(np.ptp(q[:, 0])), float(np.ptp(q[:, 1])))
        scale = max(1.0, float(np.round(extent / (VISIBLE * size))))
        for j, k in enumerate(np.linspace(0, len(q) - 1, n_robots).astype(int)):
            draw_robot(
                ax,
                model.robot,
                q[k, 0:3],
                q[k, 3 : 3 + model.robot.n_steering],
                color=color,
                alpha=0.7,
                scale=scale,
                label=f"robot, drawn x{scale:g} (to be seen)" if scale > 1 and j == 0 else None,
            )
        wheel_legend(ax, model.robot)
    legend(ax, ncol=2)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)


def plot_wheel_speeds(ax, result: WheeledSimResult) -> None:
    """Spin rate of every wheel [rad/s] against time (from the rolling constraints)."""
    t = result.t[:-1]
    for name, w in result.wheel_speeds.items():
        ax.plot(t, w, lw=1, label=name)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("wheel speed [rad/s]")
    if result.wheel_speeds:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    ax.grid(alpha=0.3)


def plot_states(ax, result: WheeledSimResult) -> None:
    """Every coordinate of q against time."""
    for i, name in enumerate(result.coordinates):
        ax.plot(result.t, result.q[:, i], lw=1, label=name)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("q [m, rad]")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    ax.grid(alpha=0.3)


def plot_residual(ax, result: WheeledSimResult, *, label: str | None = None) -> None:
    """|A^T(q) q_dot| of the applied velocity against time (log scale, floor 1e-18)."""
    ax.semilogy(result.t[:-1], np.maximum(result.residual, 1e-18), lw=1, label=label or result.model)
    if not np.any(result.residual):
        ax.text(0.5, 0.5, "no posture constraint (A has no columns)", transform=ax.transAxes, ha="center", fontsize=8)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("|A^T q_dot| [m/s]")
    ax.set_ylim(1e-18, 1.0)
    ax.grid(alpha=0.3)


def figure(nrows: int = 1, ncols: int = 1, *, size=(5.0, 4.0)):
    """A new figure (not attached to pyplot, :func:`qprr.viz.new_figure`) and its (nrows, ncols) axes."""
    nrows, ncols = as_int(nrows, "nrows", lo=1), as_int(ncols, "ncols", lo=1)
    size = as_vector(size, 2, "size")
    if not size.min() > 0.0:
        raise InputError(f"size must be (width, height) > 0 in inches, got {size.tolist()}")
    fig = new_figure((size[0] * ncols, size[1] * nrows))
    return fig, fig.subplots(nrows, ncols, squeeze=False)


def save(fig, path: str | Path, *, dpi: int = 80) -> Path:
    """Write ``fig`` to ``path`` (.png, .pdf or .svg in an existing folder, :func:`qprr.viz.figure_path`)."""
    path = figure_path(path)
    fig.savefig(path, dpi=dpi)
    return path


__all__ = [
    "COLORS",
    "VISIBLE",
    "WHEEL_NAMES",
    "draw_robot",
    "figure",
    "plot_icr",
    "plot_path",
    "plot_residual",
    "plot_states",
    "plot_wheel_speeds",
    "robot_size",
    "save",
    "wheel_legend",
]
