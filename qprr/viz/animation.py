"""Headless 3-D animation of a run (or of an IK solution path) to GIF or MP4.

:func:`animate` draws, with matplotlib on its Agg canvas (no display, no ``matplotlib.use``):
the multirotor (hub, booms, propeller discs), the arm as a polyline through its joint origins
(from Pinocchio's frames), the rotor thrusts as arrows scaled by force and coloured by the
fraction of the rotor's maximum thrust, the centre of gravity and the thrust axis (with their
distance), the trails of the base and of the end effector, the contact force at the end
effector and the payload it carries (a ball at the payload's centre of mass while its mass is not zero, the CoG
then that of the robot with the payload).  Frames are decimated to ``fps`` (a 30 s run at 1 kHz becomes 600 frames at 20 fps)
and written as they are drawn: GIF through Pillow, MP4 through ``ffmpeg`` when it is installed.
:func:`animate_result` reads the arrays of a run object (``SimResult``, :class:`~qprr.viz.run.RunLog`).
"""

from __future__ import annotations

import dataclasses
import math
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import charts as ch
from ..errors import InputError, MissingDependencyError, NonFiniteError, ShapeError, UnknownNameError
from ..model import Platform
from ..progress import Progress
from ..validation import as_array, as_real, as_settings, as_vector
from .geometry import characteristic_length, rotor_radius
from .scene import RobotPose, arm_chain, robot_pose

VIEWS = ("follow", "fixed")
"""Camera modes: "follow" centres a cube of half-width ``radius`` on the base; "fixed" frames the whole run."""

_ARM = "#1f3a5f"
_BODY = "#3f4552"
_DISC = "#4a8cf0"
_COG = "#c0392b"
_AXIS = "#7f8c8d"
_EE_TRAIL = "#e67e22"
_BASE_TRAIL = "#95a5a6"
_FORCE = "#8e44ad"
_PAYLOAD = "#16a085"
_CMAP = ((0.0, "#27ae60"), (0.6, "#f39c12"), (1.0, "#c0392b"))  # thrust colour from 0 to f_max


@dataclass(frozen=True)
class AnimationInfo:
    """What :func:`animate` wrote: ``path``, ``frames`` at ``fps`` [1/s], covering ``duration`` [s] of the run, in ``wall_time`` [s]."""

    path: Path
    frames: int
    fps: float
    duration: float
    wall_time: float
    writer: str


@dataclass(frozen=True)
class CarriedPayload:
    """The payload the end effector carries during a run: ``mass`` (n,) [kg] per sample (0: none) at ``com_ee`` (n, 3)
    [m] in the end-effector frame (None: at its origin), as a run logs it (``SimResult.series["payload_mass"]`` and
    ``["payload_com_ee"]``)."""

    mass: np.ndarray
    com_ee: np.ndarray | None = None

    def __post_init__(self) -> None:  # checked however it is built; the sample count is checked by the animation
        mass = as_array(self.mass, "payload mass", finite=True, ndim=1)
        if mass.shape[0] < 1 or not np.all(mass >= 0.0):
            raise InputError(f"payload mass must hold one mass >= 0 kg per sample, got {mass.tolist()!r:.80}")
        object.__setattr__(self, "mass", mass)
        if self.com_ee is not None:
            com = as_array(self.com_ee, "payload com_ee", finite=True, ndim=2)
            if com.shape != (mass.shape[0], 3):
                raise ShapeError(f"payload com_ee must have shape ({mass.shape[0]}, 3) (one point [m, end-effector frame] per mass), got {com.shape}")
            object.__setattr__(self, "com_ee", com)

    def checked(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(mass (n,), com_ee (n, 3)) for a run of ``n`` samples."""
        if self.mass.shape != (n,):
            raise ShapeError(f"payload mass must have shape ({n},) (one value per sample of the run), got {self.mass.shape}")
        return self.mass, np.zeros((n, 3)) if self.com_ee is None else self.com_ee


# ============================================================================ inputs
def _check_inputs(platform: Platform, t, xi, f, contact):
    if not isinstance(platform, Platform):
        raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
    t = as_array(t, "t")
    if t.ndim != 1 or t.shape[0] < 1:
        raise ShapeError(f"t must have shape (n,) with n >= 1, got {t.shape}")
    n = t.shape[0]
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0.0):
        raise InputError("t must be finite and non-decreasing [s]")
    xi = as_array(xi, "xi")
    if xi.shape != (n, platform.n_xi):
        raise ShapeError(
            f"xi must have shape ({n}, {platform.n_xi}) for platform {platform.name!r} (6 + {platform.n_arm} arm joints), got {xi.shape}"
        )
    out = [t, xi]
    for name, a, width in (("f", f, platform.n_rotors), ("contact_force_world", contact, 3)):
        if a is not None:
            a = as_array(a, name)
            if a.shape != (n, width):
                raise ShapeError(f"{name} must have shape ({n}, {width}), got {a.shape}")
        out.append(a)
    for name, a in zip(("xi", "f", "contact_force_world"), out[1:]):
        if a is not None and not np.all(np.isfinite(a)):
            raise NonFiniteError(f"{name} must be finite")
    return out


def _positive(name: str, value) -> float:
    return as_real(value, name, positive=True)


def frame_indices(t: np.ndarray, fps: float, speed: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(times, indices): one frame every ``speed / fps`` seconds of the run, each showing the last sample at or before its time."""
    t = as_array(t, "t", finite=True, ndim=1)
    if t.shape[0] == 0:
        raise InputError("t must hold at least one sample time")
    fps, speed = _positive("fps", fps), _positive("speed", speed)
    span = float(t[-1] - t[0])
    n = int(math.floor(span * fps / speed + 1e-9)) + 1
    times = t[0] + np.arange(n) * (speed / fps)
    idx = np.clip(np.searchsorted(t, times, side="right") - 1, 0, t.shape[0] - 1)
    return times, idx


# ============================================================================ writers
class _GifWriter:
    """Frames quantised to one global palette (the first frame's and the artists' colours), streamed to the file.

    Each frame after the first stores only the box of pixels that changed (Pillow's GIF header
    and frame encoders, ``PIL.GifImagePlugin.getheader`` / ``getdata``): memory stays at two frames.
    """

    def __init__(self, path: Path, fps: float, swatch: np.ndarray):
        from PIL import GifImagePlugin, Image

        self.Image, self.gif = Image, GifImagePlugin
        self.path, self.swatch = path, swatch
        self.duration = int(round(1000.0 / fps))
        self.palette = None
        self.previous = None
        self.fp = None

    def add(self, rgba: np.ndarray) -> None:
        Image = self.Image
        im = Image.frombuffer("RGBA", (rgba.shape[1], rgba.shape[0]), rgba, "raw", "RGBA", 0, 1).convert("RGB")
        if self.palette is None:  # first frame plus a strip of every artist colour
            w = rgba.shape[1]
            strip = np.broadcast_to(np.resize(self.swatch, (w, 3)), (8, w, 3)).astype(np.uint8)
            composite = Image.fromarray(np.concatenate([np.asarray(im), strip], axis=0))
            self.palette = composite.quantize(colors=256, method=Image.Quantize.MEDIANCUT)
        frame = im.quantize(palette=self.palette, dither=Image.Dither.NONE)
        index = np.asarray(frame)
        if self.fp is None:
            self.fp = open(self.path, "wb")
            header, _ = self.gif.getheader(frame, None, {"loop": 0, "duration": self.duration})
            for chunk in header:
                self.fp.write(chunk)
            box = (0, 0, index.shape[1], index.shape[0])
        else:
            changed = index != self.previous
            rows, cols = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
            box = (0, 0, 1, 1) if rows.size == 0 else (int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1)
        part = frame if box == (0, 0, index.shape[1], index.shape[0]) else frame.crop(box)
        for chunk in self.gif.getdata(part, offset=box[0:2], duration=self.duration, disposal=1):
            self.fp.write(chunk)
        self.previous = index

    def close(self) -> None:
        if self.fp is not None:
            self.fp.write(b";")
            self.fp.close()
            self.fp = None


class _FfmpegWriter:
    """Raw RGBA frames piped to ffmpeg (H.264 when available, ffmpeg's MP4 default otherwise)."""

    def __init__(self, path: Path, fps: float, size: tuple[int, int], exe: str):
        w, h = size
        cmd = [
            exe,
            "-loglevel",
            "error",
            "-y",
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgba",
            "-s",
            f"{w}x{h}",
            "-r",
            f"{fps:g}",
            "-i",
            "-",
            "-vf",
            "pad=ceil(iw/2)*2:ceil(ih/2)*2",
            "-pix_fmt",
            "yuv420p",
            str(path),
        ]
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE)

    def add(self, rgba: np.ndarray) -> None:
        self.proc.stdin.write(np.ascontiguousarray(rgba).tobytes())

    def close(self) -> None:
        _, err = self.proc.communicate()
        if self.proc.returncode != 0:
            raise RuntimeError(f"ffmpeg failed ({self.proc.returncode}): {err.decode(errors='replace').strip()}")


def _writer_for(path: Path, fps: float, size: tuple[int, int], swatch: np.ndarray):
    suffix = path.suffix.lower()
    if suffix == ".gif":
        return _GifWriter(path, fps, swatch), "gif (Pillow)"
    if suffix == ".mp4":
        import matplotlib as mpl

        exe = shutil.which(mpl.rcParams.get("animation.ffmpeg_path", "ffmpeg")) or shutil.which("ffmpeg")
        if exe is None:
            raise MissingDependencyError("ffmpeg", "MP4 animations", "apt-get install ffmpeg (or write a .gif, which needs only Pillow)")
        return _FfmpegWriter(path, fps, size, exe), "mp4 (ffmpeg)"
    raise InputError(f"animation files end in .gif or .mp4, got {str(path)!r}")


# ============================================================================ drawing helpers
def _circle(n: int = 20) -> np.ndarray:
    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.stack([np.cos(a), np.sin(a)], axis=1)


def _disc(centre: np.ndarray, normal: np.ndarray, radius: float, unit: np.ndarray) -> np.ndarray:
    """Vertices (m, 3) of a circle of ``radius`` about ``centre`` normal to ``normal``."""
    e1 = np.cross(normal, [1.0, 0.0, 0.0])
    if np.linalg.norm(e1) < 1e-6:
        e1 = np.cross(normal, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    return centre + radius * (unit[:, 0:1] * e1 + unit[:, 1:2] * e2)


def _arrows(starts: np.ndarray, vectors: np.ndarray, side: np.ndarray, head: float = 0.05) -> np.ndarray:
    """Segments (3 m, 2, 3) of m arrows: the shaft and two head strokes in the plane of ``side``."""
    segs = []
    for s, v in zip(starts, vectors):
        length = float(np.linalg.norm(v))
        e = s + v
        if length < 1e-9:
            segs += [[s, s], [s, s], [s, s]]
            continue
        u = v / length
        w = side - (side @ u) * u
        nw = float(np.linalg.norm(w))
        w = w / nw if nw > 1e-9 else np.cross(u, [0.0, 0.0, 1.0]) / max(np.linalg.norm(np.cross(u, [0.0, 0.0, 1.0])), 1e-9)
        h = min(0.3 * length, head)  # head [m]: at most a fixed share of the platform's size
        segs += [[s, e], [e, e - h * u + 0.5 * h * w], [e, e - h * u - 0.5 * h * w]]
    return np.array(segs)


def _grid_step(half: float) -> float:
    """A round grid spacing [m] (1, 2 or 5 x 10^k) giving about four lines across 2 ``half``."""
    raw = half / 2.0
    k = math.floor(math.log10(raw))
    return min((m * 10.0**k for m in (1.0, 2.0, 5.0, 10.0)), key=lambda s: abs(math.log(s / raw)))


def _floor_grid(centre: np.ndarray, half: float, step: float) -> np.ndarray:
    """Segments (m, 2, 3) of a grid every ``step`` on the floor (z = centre z - half) of the cube of half-width ``half``."""
    lo, hi, z = centre[0:2] - half, centre[0:2] + half, centre[2] - half
    segs = [[(x, lo[1], z), (x, hi[1], z)] for x in np.arange(math.ceil(lo[0] / step), math.floor(hi[0] / step) + 1) * step]
    segs += [[(lo[0], y, z), (hi[0], y, z)] for y in np.arange(math.ceil(lo[1] / step), math.floor(hi[1] / step) + 1) * step]
    return np.array(segs).reshape(-1, 2, 3)


def _cog_distance(pose: RobotPose) -> float:
    """Distance [m] of the CoG from the thrust axis line."""
    d = pose.com_world - pose.axis_point_world
    return float(np.linalg.norm(d - (d @ pose.axis_dir_world) * pose.axis_dir_world))


# ============================================================================ animation
@dataclass(frozen=True)
class _Look:
    """The sizes of a drawing: the robot's size ``L`` [m], the "follow" cube's half-width ``radius`` [m], the arrows'
    ``thrust_scale`` and ``force_scale`` [m/N], the camera ``view`` and the trail's length ``keep`` in frames (None:
    the whole past)."""

    L: float
    radius: float
    thrust_scale: float
    force_scale: float
    view: str
    keep: int | None


def _pixels(size) -> tuple[int, int]:
    """(width, height) [px] of the video, each between 16 and 4096."""
    v = as_vector(size, 2, "size (width, height) in pixels")
    if not np.all(np.isfinite(v)):
        raise InputError(f"size must be (width, height) in pixels, got {size!r}")
    width, height = int(v[0]), int(v[1])
    if not (16 <= width <= 4096 and 16 <= height <= 4096):
        raise InputError(f"size must be between 16 and 4096 pixels per side, got {size!r}")
    return width, height


def _look(platform: Platform, fps: float, speed: float, view: str, radius, trail, thrust_scale, force_scale) -> _Look:
    """The checked sizes of :func:`animate` (defaults from the platform's size and hover thrust)."""
    L = characteristic_length(platform)
    radius = 1.3 * L if radius is None else _positive("radius", radius)
    hover = platform.total_mass * platform.g / platform.n_rotors
    thrust_scale = 0.6 * L / hover if thrust_scale is None else _positive("thrust_scale", thrust_scale)
    force_scale = thrust_scale if force_scale is None else _positive("force_scale", force_scale)
    if trail is not None and not (isinstance(trail, (int, float)) and math.isfinite(trail) and trail >= 0):
        raise InputError(f"trail must be None or a number of seconds >= 0, got {trail!r}")
    keep = None if trail is None else max(1, int(round(trail * fps / speed)) + 1)
    return _Look(L, radius, thrust_scale, force_scale, view, keep)


def _swatch(cmap) -> np.ndarray:
    """Every colour the artists draw (RGB, 0-255): the GIF palette keeps them."""
    colours = [cmap(x)[:3] for x in np.linspace(0, 1, 24)]
    named = (_ARM, _BODY, _DISC, _COG, _AXIS, _EE_TRAIL, _BASE_TRAIL, _FORCE, _PAYLOAD)
    colours += [tuple(int(c[i : i + 2], 16) / 255 for i in (1, 3, 5)) for c in named]
    return np.array(colours) * 255


def _fixed_box(poses: list[RobotPose], L: float) -> tuple[np.ndarray, float]:
    """(centre [m, world], half-width [m]) of the cube holding every rotor and arm point of the run, with 0.3 ``L`` margin."""
    pts = np.concatenate([np.concatenate([p.rotor_world, p.arm_world]) for p in poses])
    lo, hi = pts.min(axis=0) - 0.3 * L, pts.max(axis=0) + 0.3 * L
    return 0.5 * (lo + hi), 0.5 * float((hi - lo).max())


class _Scene:
    """The figure of an animation on its Agg canvas (no display, no backend switch): a 3-D axes with the artists each
    frame moves, the title and legend drawn once, two text lines that change."""

    def __init__(self, platform: Platform, poses: list[RobotPose], look: _Look, size: tuple[int, int]) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.colors import LinearSegmentedColormap
        from matplotlib.figure import Figure

        self.look, self.platform = look, platform
        dpi = 100
        self.fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
        self.canvas = FigureCanvasAgg(self.fig)
        self.ax = self.fig.add_axes((0.0, 0.0, 1.0, 0.88), projection="3d")
        self.ax.view_init(elev=22, azim=-58)
        self.ax.set_box_aspect((1.0, 1.0, 1.0))
        # "fixed": the cube framing the whole run; "follow": a cube of half-width radius moved onto the base each frame
        self.centre, self.half = _fixed_box(poses, look.L) if look.view == "fixed" else (None, look.radius)
        self.step = _grid_step(self.half)
        self._bare_axes()
        self.cmap = LinearSegmentedColormap.from_list("thrust", _CMAP)
        self.unit = _circle()
        self.disc_r = rotor_radius(platform)
        self.hub_r = 0.25 * min(math.hypot(*r.position_body[0:2]) for r in platform.rotors) or 0.05
        self._artists()

    def _bare_axes(self) -> None:
        """No ticks (they are most of a 3-D frame's drawing time): a floor grid every ``step`` metres instead."""
        from matplotlib.ticker import NullLocator

        ax = self.ax
        for axis, label in zip((ax.xaxis, ax.yaxis, ax.zaxis), ("x", "y", "z")):
            axis.set_pane_color((0.96, 0.96, 0.97, 1.0))
            axis.set_major_locator(NullLocator())
            axis.set_label_text(label)
            axis.labelpad = -12
        ax.grid(False)

    def _artists(self) -> None:
        from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

        ax = self.ax
        nothing = [np.zeros((2, 3))]  # placeholders until the first frame sets the geometry
        self.hub = Poly3DCollection(nothing, facecolor=_BODY, edgecolor=_BODY, alpha=0.9)
        self.discs = Poly3DCollection(nothing, facecolor=_DISC, edgecolor=_DISC, alpha=0.3, linewidths=0.5)
        self.booms = Line3DCollection(nothing, colors=_BODY, linewidths=2.0)
        self.thrusts = Line3DCollection(nothing, linewidths=2.2)
        self.force = Line3DCollection(nothing, colors=_FORCE, linewidths=2.4)
        self.floor = Line3DCollection(nothing, colors="#c8c8cc", linewidths=0.6)
        for artist in (self.floor, self.hub, self.discs, self.booms, self.thrusts, self.force):
            ax.add_collection3d(artist, autolim=False)
        (self.arm_line,) = ax.plot([], [], [], "-o", color=_ARM, lw=3.0, ms=3.5, mfc="#f5f5f5", mec="#1f3a5f", zorder=5)
        (self.ee_dot,) = ax.plot([], [], [], "o", color="#c0392b", ms=5)
        (self.payload_dot,) = ax.plot([], [], [], "o", color=_PAYLOAD, ms=10, mec="#0b5345", mew=0.8, zorder=7)
        (self.cog_dot,) = ax.plot([], [], [], "X", color=_COG, ms=8, mec="white", mew=0.6, zorder=6)
        (self.axis_line,) = ax.plot([], [], [], "--", color=_AXIS, lw=1.0)
        (self.ee_trail,) = ax.plot([], [], [], "-", color=_EE_TRAIL, lw=1.0, alpha=0.8)
        (self.base_trail,) = ax.plot([], [], [], "-", color=_BASE_TRAIL, lw=1.0, alpha=0.8)

    def texts(self, thrusts: bool, contact: bool, title: str, payload: bool = False) -> None:
        """The legend (thrust, contact and payload entries when drawn), the title, the grid spacing and the two changing
        lines."""
        from matplotlib.lines import Line2D

        handles = [
            Line2D([], [], color=_ARM, lw=3, marker="o", ms=3, mfc="#f5f5f5", label="arm (joint origins)"),
            Line2D([], [], color=_COG, marker="X", lw=0, label="CoG"),
            Line2D([], [], color=_AXIS, ls="--", label="thrust axis"),
            Line2D([], [], color=_EE_TRAIL, label="end-effector trail"),
        ]
        if thrusts:
            handles.append(Line2D([], [], color=self.cmap(0.5), lw=2, label="thrust (colour: f / f_max)"))
        if contact:
            handles.append(Line2D([], [], color=_FORCE, lw=2, label="contact force"))
        if payload:
            handles.append(Line2D([], [], color=_PAYLOAD, marker="o", lw=0, ms=7, mec="#0b5345", label="payload (while carried)"))
        fig = self.fig
        fig.legend(handles=handles, loc="upper right", ncols=2, fontsize=6.5, framealpha=0.8, borderaxespad=0.3)
        fig.text(0.01, 0.975, title, fontsize=9, va="top")
        fig.text(0.99, 0.01, f"grid {self.step:g} m", fontsize=7, ha="right", color="#555555")
        self.head = fig.text(0.01, 0.93, "", fontsize=7.5, va="top", family="monospace")
        self.foot = fig.text(0.01, 0.02, "", fontsize=7.5, family="monospace", color="#333333")

    def _frame_box(self, centre: np.ndarray) -> None:
        """The cube of half-width ``self.half`` about ``centre`` and its floor grid."""
        half = self.half
        self.ax.set_xlim(centre[0] - half, centre[0] + half)
        self.ax.set_ylim(centre[1] - half, centre[1] + half)
        self.ax.set_zlim(centre[2] - half, centre[2] + half)
        self.floor.set_segments(_floor_grid(centre, half, self.step))

    def freeze(self) -> None:
        """Fix a "fixed" view's box, then draw the title and legend once: each frame redraws only the axes and the lines."""
        if self.look.view == "fixed":
            self._frame_box(self.centre)
        self.ax.set_visible(False)
        self.canvas.draw()
        self.background = self.canvas.copy_from_bbox(self.fig.bbox)
        self.ax.set_visible(True)

    def robot(self, pose: RobotPose) -> None:
        """The multirotor, the arm, the end effector, the CoG and the thrust axis at ``pose``."""
        p, R, L = pose.p_base_world, pose.R_base_world, self.look.L
        if self.look.view == "follow":
            self._frame_box(p)
        self.hub.set_verts([_disc(p, R[:, 2], self.hub_r, self.unit)])
        self.discs.set_verts([_disc(c, a, self.disc_r, self.unit) for c, a in zip(pose.rotor_world, pose.rotor_axis_world)])
        self.booms.set_segments([[p, c] for c in pose.rotor_world])
        a = pose.arm_world
        self.arm_line.set_data_3d(a[:, 0], a[:, 1], a[:, 2])
        self.ee_dot.set_data_3d([a[-1, 0]], [a[-1, 1]], [a[-1, 2]])
        c = pose.com_world
        self.cog_dot.set_data_3d([c[0]], [c[1]], [c[2]])
        ends = np.array([pose.axis_point_world - 1.2 * L * pose.axis_dir_world, pose.axis_point_world + 1.5 * L * pose.axis_dir_world])
        self.axis_line.set_data_3d(ends[:, 0], ends[:, 1], ends[:, 2])

    def trails(self, ee_hist: np.ndarray, base_hist: np.ndarray, k: int) -> None:
        """The end effector's and the base's paths up to frame ``k`` (the last ``keep`` frames)."""
        start = 0 if self.look.keep is None else max(0, k + 1 - self.look.keep)
        self.ee_trail.set_data_3d(ee_hist[start : k + 1, 0], ee_hist[start : k + 1, 1], ee_hist[start : k + 1, 2])
        self.base_trail.set_data_3d(base_hist[start : k + 1, 0], base_hist[start : k + 1, 1], base_hist[start : k + 1, 2])

    def thrust_arrows(self, pose: RobotPose, fk: np.ndarray, f_ref: np.ndarray) -> None:
        """Rotor thrusts ``fk`` [N] as arrows along the rotor axes, coloured by ``fk / f_ref``; their values in the foot line."""
        R, L = pose.R_base_world, self.look.L
        self.thrusts.set_segments(_arrows(pose.rotor_world, fk[:, None] * self.look.thrust_scale * pose.rotor_axis_world, R[:, 0], 0.12 * L))
        self.thrusts.set_color(np.repeat([self.cmap(x) for x in np.clip(fk / f_ref, 0.0, 1.0)], 3, axis=0))
        self.foot.set_text("f [N] " + " ".join(f"{v:.2f}" for v in fk))

    def payload_ball(self, p_world: np.ndarray, mass: float) -> None:
        """The payload at ``p_world`` [m] while its ``mass`` [kg] is not zero (nothing drawn otherwise)."""
        if mass > 0.0:
            self.payload_dot.set_data_3d([p_world[0]], [p_world[1]], [p_world[2]])
        else:
            self.payload_dot.set_data_3d([], [], [])

    def contact_arrow(self, pose: RobotPose, fc_world: np.ndarray) -> None:
        """The contact force ``fc_world`` [N, world axes] as an arrow at the end effector."""
        arrow = (self.look.force_scale * fc_world)[None, :]
        self.force.set_segments(_arrows(pose.ee_world[None, :], arrow, pose.R_base_world[:, 2], 0.12 * self.look.L))

    def image(self, line: str) -> np.ndarray:
        """The frame's pixels (RGBA) with ``line`` as its head line: the axes and the two lines over the background."""
        self.head.set_text(line)
        self.canvas.restore_region(self.background)
        self.fig.draw_artist(self.ax)
        self.fig.draw_artist(self.head)
        self.fig.draw_artist(self.foot)
        return np.asarray(self.canvas.buffer_rgba())


@dataclass
class _Series:
    """What the frames show: ``times`` [s], the sample index ``idx`` of each, its ``poses``, the thrusts ``f`` [N] and the
    end-effector contact force ``contact`` [N, world] per sample (or None), and the thrust of a full colour ``f_ref`` [N]."""

    times: np.ndarray
    idx: np.ndarray
    poses: list
    f: np.ndarray | None
    contact: np.ndarray | None
    f_ref: np.ndarray
    payload_mass: np.ndarray | None = None
    payload_world: np.ndarray | None = None


def _series(platform: Platform, t, xi, f, contact, fps: float, speed: float, payload=None) -> _Series:
    """Every frame's geometry first (Pinocchio: microseconds per frame); ``payload``: (mass (n,), com_ee (n, 3)) or None."""
    times, idx = frame_indices(t, fps, speed)
    data = platform.data()
    chain = arm_chain(platform)
    poses, where = [], []
    for k in idx:
        pose = robot_pose(platform, data, ch.xi_to_q(xi[k]), chain)
        if payload is not None:
            pose, p_world = _with_payload(platform, data, pose, payload[0][k], payload[1][k])
            where.append(p_world)
        poses.append(pose)
    hover = platform.total_mass * platform.g / platform.n_rotors
    f_max = platform.thrust_max
    f_ref = np.where(np.isfinite(f_max), f_max, 2.0 * hover)
    if payload is None:
        return _Series(times, idx, poses, f, contact, f_ref)
    return _Series(times, idx, poses, f, contact, f_ref, payload[0][idx], np.array(where))


def _with_payload(platform: Platform, data, pose: RobotPose, mass: float, com_ee: np.ndarray) -> tuple[RobotPose, np.ndarray]:
    """(``pose`` with the CoG of robot and payload, the payload's position [m, world]); ``data`` holds ``pose``'s kinematics."""
    frame = platform.model.frames[platform.ee_frame]
    p_world = data.oMi[frame.parentJoint].act(frame.placement.act(np.asarray(com_ee, dtype=float)))
    m_robot = platform.total_mass
    com = (m_robot * pose.com_world + mass * p_world) / (m_robot + mass)
    return dataclasses.replace(pose, com_world=com), np.array(p_world)


def _write_frames(scene: _Scene, series: _Series, writer, bar) -> None:
    """Draw each frame and hand it to ``writer``."""
    ee_hist = np.array([p.ee_world for p in series.poses])
    base_hist = np.array([p.p_base_world for p in series.poses])
    for k, (pose, i) in enumerate(zip(series.poses, series.idx)):
        scene.robot(pose)
        scene.trails(ee_hist, base_hist, k)
        line = f"t = {series.times[k]:6.2f} s   CoG to axis {1000 * _cog_distance(pose):5.1f} mm"
        if series.f is not None:
            scene.thrust_arrows(pose, series.f[i], series.f_ref)
        if series.contact is not None:
            fc = series.contact[i]
            scene.contact_arrow(pose, fc)
            line += f"   |F| {np.linalg.norm(fc):.2f} N"
        if series.payload_mass is not None:
            scene.payload_ball(series.payload_world[k], series.payload_mass[k])
            line += f"   payload {series.payload_mass[k]:.3g} kg"
        writer.add(scene.image(line))
        bar.update()


@dataclass(frozen=True)
class AnimationOptions:
    """How :func:`animate` draws a run (each field also a keyword of :func:`animate`).

    fps : frames per second of the file; ``speed``: run seconds per video second (2: twice as fast).
    size : (width, height) in pixels.
    view : "follow" (a cube of half-width ``radius`` [m] centred on the base, default 1.3 x the
        robot's size) or "fixed" (the whole run).
    trail : seconds of base and end-effector trail (None: the whole past; 0: none).
    thrust_scale : metres per newton of the rotor arrows (default: the hover thrust drawn 0.6 x the robot's size);
        ``force_scale``: of the contact force (default ``thrust_scale``).
    title : text above the plot (default: the platform's name).  progress : a progress bar on stderr.
    """

    fps: float = 20.0
    speed: float = 1.0
    size: tuple[int, int] = (640, 480)
    view: str = "follow"
    radius: float | None = None
    trail: float | None = None
    thrust_scale: float | None = None
    force_scale: float | None = None
    title: str | None = None
    progress: bool = False

    def __post_init__(self) -> None:  # what needs no platform to check, checked however the options are built
        object.__setattr__(self, "fps", _positive("fps", self.fps))
        object.__setattr__(self, "speed", _positive("speed", self.speed))
        object.__setattr__(self, "size", _pixels(self.size))
        if self.view not in VIEWS:
            raise UnknownNameError("view", self.view, VIEWS)
        for key in ("radius", "thrust_scale", "force_scale"):
            if self.__dict__[key] is not None:
                object.__setattr__(self, key, _positive(key, self.__dict__[key]))
        trail = self.trail
        if trail is not None and not (isinstance(trail, (int, float)) and not isinstance(trail, bool) and math.isfinite(trail) and trail >= 0):
            raise InputError(f"trail must be None or a number of seconds >= 0, got {trail!r}")


def animate(
    platform: Platform,
    t,
    xi,
    path: str | Path,
    f=None,
    contact_force_world=None,
    payload: CarriedPayload | None = None,
    options: AnimationOptions | None = None,
    **settings,
) -> AnimationInfo:
    """Animate a run of ``platform`` to ``path`` (``.gif`` with Pillow, ``.mp4`` with ffmpeg).

    Parameters
    ----------
    t : (n,) times [s], non-decreasing.
    xi : (n, 6 + n_arm) thesis coordinates (:mod:`qprr.charts`).
    f : optional (n, n_rotors) rotor thrusts [N]: arrows along each rotor's axis, ``thrust_scale``
        metres per newton (default: the hover thrust drawn 0.6 x the robot's size), coloured by
        f / f_max (green to red).
    contact_force_world : optional (n, 3) force [N] on the end effector, world axes, drawn at the
        end effector with ``force_scale`` m/N (default ``thrust_scale``).
    payload : optional :class:`CarriedPayload`: a ball where the payload is while its mass is not zero (and the CoG
        drawn is that of the robot with the payload).
    options : an :class:`AnimationOptions` (frame rate, speed, size, view, trail, scales, title, progress), and/or
        its fields as keywords, which replace the options' (``animate(p, t, xi, "run.gif", fps=10, view="fixed")``).
    """
    o = as_settings(options, AnimationOptions, "options", **settings)
    t, xi, f, contact = _check_inputs(platform, t, xi, f, contact_force_world)
    fps, speed, size, title, progress = o.fps, o.speed, o.size, o.title, o.progress
    path = Path(path)
    look = _look(platform, fps, speed, o.view, o.radius, o.trail, o.thrust_scale, o.force_scale)
    t0 = time.perf_counter()
    carried = None
    if payload is not None:
        if not isinstance(payload, CarriedPayload):
            raise InputError(f"payload must be a qprr.viz.animation.CarriedPayload (mass per sample [kg], com_ee), got {type(payload).__name__}")
        carried = payload.checked(t.shape[0])
    series = _series(platform, t, xi, f, contact, fps, speed, carried)
    scene = _Scene(platform, series.poses, look, size)
    scene.texts(f is not None, contact is not None, platform.name if title is None else str(title), payload=carried is not None)
    scene.freeze()

    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.stem + ".partial" + path.suffix)
    writer, kind = _writer_for(partial, fps, size, _swatch(scene.cmap))
    bar = Progress(len(series.poses), f"animating {path.name}", quiet=not progress, unit="frame")
    try:
        _write_frames(scene, series, writer, bar)
        writer.close()
        partial.replace(path)
    except BaseException:
        writer.close()
        partial.unlink(missing_ok=True)
        raise
    finally:
        bar.close()
    times = series.times
    return AnimationInfo(path, len(series.poses), fps, float(times[-1] - times[0]), time.perf_counter() - t0, kind)


def animate_result(platform: Platform, result, path: str | Path, **options) -> AnimationInfo:
    """:func:`animate` a run object (``SimResult`` or :class:`~qprr.viz.run.RunLog`): its ``t``, ``xi``, ``f``
    and, when logged, the force part of ``contact_wrench_world`` and the payload (``payload_mass``, ``payload_com_ee``);
    ``options`` go to :func:`animate`."""
    from .run import as_run

    run = as_run(result)
    if run.xi.shape[1] != platform.n_xi:
        raise ShapeError(
            f"the run has {run.xi.shape[1]} coordinates per sample (platform {run.platform or '?'!r}); platform {platform.name!r} has {platform.n_xi}"
        )
    if run.f is not None and run.f.shape[1] != platform.n_rotors:
        raise ShapeError(f"the run logs {run.f.shape[1]} rotor thrusts per sample; platform {platform.name!r} has {platform.n_rotors} rotors")
    contact = None if run.contact_wrench_world is None else run.contact_wrench_world[:, 0:3]
    payload = None if run.payload_mass is None else CarriedPayload(run.payload_mass, run.payload_com_ee)
    return animate(platform, run.t, run.xi, path, f=run.f, contact_force_world=contact, payload=payload, **options)
