"""Interactive browser viewer of a platform (the virtual prototype's GUI of Thesis Annex A, Fig. A.8), on viser.

``qprr view [PLATFORM]`` (or :class:`Viewer` from Python) starts a local web server on
127.0.0.1 (never another interface) and shows, through Pinocchio's
``pinocchio.visualize.ViserVisualizer``:

* the robot with its visual geometry (:func:`qprr.viz.visual_model`);
* a slider for every thesis coordinate (x, y, z, phi, theta, psi and each arm joint within its
  limits): forward kinematics, as the sliders of Fig. A.8;
* a draggable end-effector target solved live by the strict task-priority IK
  (:func:`qprr.viz.ik_solve`: end-effector position or pose > hover > CoG on the thrust axis >
  posture; the hover and CoG levels are switches), with the IK outcome;
* the centre of gravity, the thrust axis and, as arrows, the rotor thrusts that hold the
  configuration still with their margins to the thrust bounds (:func:`qprr.viz.hover_report`);
* a player for a saved run (a result file of :meth:`qprr.sim.SimResult.save`): time slider, play/pause,
  speed, the logged thrusts and contact force, the end-effector trail.

The same operations are methods (:meth:`Viewer.set_xi`, :meth:`Viewer.set_joint`,
:meth:`Viewer.solve_target`, :meth:`Viewer.load_run`, :meth:`Viewer.show_time`), which the
browser test uses.  Needs the ``viewer`` extra: ``pip install 'qprr[viewer]'`` (viser).
"""

from __future__ import annotations

import contextlib
import io
import logging
import math
import os
import socket
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..errors import MissingDependencyError, PortInUseError

try:
    import viser
    from pinocchio.visualize import ViserVisualizer
except ModuleNotFoundError as exc:  # pragma: no cover - exercised only without the extra
    if exc.name != "viser":
        raise
    raise MissingDependencyError("viser", "the browser viewer (qprr view)", "pip install 'qprr[viewer]'") from exc

from .. import charts as ch
from ..actuation import Allocator
from ..errors import InputError, ShapeError, UnknownNameError
from ..ik import IKResult
from ..kinematics import cog_offset_body
from ..model import Platform
from ..validation import as_vector
from .geometry import characteristic_length, rotor_radius, visual_model
from .ikpath import ik_solve
from .run import RunLog, as_run, load_run
from .scene import HoverReport, RobotPose, arm_chain, hover_report, robot_pose

HOST = "127.0.0.1"
"""The only interface the viewer listens on."""

_THRUST_OK = np.array([39, 174, 96])
_THRUST_LOW = np.array([243, 156, 18])
_THRUST_BAD = np.array([192, 57, 43])


class _DropAbortedHandshakes(logging.Filter):
    """Browsers open and drop speculative connections; websockets logs each as a traceback."""

    def filter(self, record: logging.LogRecord) -> bool:
        return record.getMessage() != "opening handshake failed"


_HANDSHAKE_FILTER = _DropAbortedHandshakes()


def check_port_free(port: int) -> None:
    """Raise :class:`~qprr.errors.PortInUseError` if TCP ``port`` on 127.0.0.1 cannot be bound."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((HOST, port))
        except OSError as exc:
            raise PortInUseError(
                f"port {port} on {HOST} is already in use ({exc.strerror}); stop the program using it or choose another with --port"
            ) from None


class Viewer:
    """The browser viewer of ``platform`` (see the module docstring).

    Parameters
    ----------
    platform : the :class:`~qprr.model.Platform` to show.
    port : TCP port on 127.0.0.1 (0: any free port; see :attr:`url`).  A port in use raises
        :class:`~qprr.errors.PortInUseError` (viser would silently take the next one).
    xi : initial thesis coordinates (default: the neutral arm, level, 1 m above the origin).
    run : optional run to load in the player (a path to a ``.npz`` or a :class:`RunLog`).
    hover, cog : initial state of the IK's hover and CoG switches.
    verbose : print the address.
    """

    def __init__(
        self, platform: Platform, *, port: int = 8080, xi=None, run=None, hover: bool = True, cog: bool = True, verbose: bool = True
    ) -> None:
        if not isinstance(platform, Platform):
            raise InputError(f"platform must be a qprr Platform, got {type(platform).__name__}")
        if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
            raise InputError(f"port must be an integer in [0, 65535], got {port!r}")
        self.platform = platform
        self._lock = threading.RLock()
        self._syncing = False
        self._data = platform.data()
        self._chain = arm_chain(platform)
        self._allocator = Allocator(platform)
        self._size = characteristic_length(platform)
        if xi is None:
            xi = platform.neutral_xi()
            xi[2] = 1.0
        self._xi = ch.as_xi(xi, "xi", platform.n_xi).copy()
        self.last_ik: IKResult | None = None
        self.hover_state: HoverReport | None = None
        self.pose: RobotPose | None = None
        self.run: RunLog | None = None
        self._run_time = 0.0
        self._pending_target = None
        self._ik_busy = False
        self._closed = False
        self._player_stop = threading.Event()
        self._player_thread: threading.Thread | None = None

        if port != 0:
            check_port_free(port)
        logging.getLogger("websockets.server").addFilter(_HANDSHAKE_FILTER)  # adding the same filter twice is a no-op
        with contextlib.redirect_stdout(io.StringIO()):  # viser's banner: the address is printed below
            self.server = viser.ViserServer(host=HOST, port=port, label=f"qprr: {platform.name}", verbose=False)
        self.port = int(self.server.get_port())
        if port != 0 and self.port != port:
            self.server.stop()
            raise PortInUseError(f"port {port} on {HOST} was taken while the viewer started (viser moved to {self.port}); choose another with --port")
        try:
            self._build_scene()
            self._build_gui(hover, cog)
            self._apply(move_target=True)
            if run is not None:
                self.load_run(run)
        except BaseException:
            self.server.stop()
            raise
        if verbose:
            print(f"qprr viewer of {platform.name}: {self.url}  (Ctrl-C to stop)", flush=True)

    # ------------------------------------------------------------------ setup
    @property
    def url(self) -> str:
        """Address of the viewer page."""
        return f"http://{HOST}:{self.port}"

    def _build_scene(self) -> None:
        p, L, scene = self.platform, self._size, self.server.scene
        geom = visual_model(p)
        self.visualizer = ViserVisualizer(p.model, pin.GeometryModel(), geom)
        self.visualizer.initViewer(viewer=self.server)
        self.visualizer.loadViewerModel(rootNodeName="/robot")
        scene.set_up_direction("+z")
        scene.add_grid("/ground", width=6.0, height=6.0, cell_size=0.25, plane="xy")
        look_at, position = camera_framing(robot_pose(p, self._data, ch.xi_to_q(self._xi), self._chain), rotor_radius(p), CAMERA_FOV)
        self.server.initial_camera.fov = CAMERA_FOV
        self.server.initial_camera.look_at = tuple(look_at)
        self.server.initial_camera.position = tuple(position)
        self._cog = scene.add_icosphere("/markers/cog", radius=0.04 * L + 0.01, color=(200, 30, 30))
        self._cog_label = scene.add_label("/markers/cog/label", "CoG")
        self._axis = scene.add_line_segments("/markers/thrust_axis", np.zeros((1, 2, 3)), (90, 90, 90), thickness=0.004)
        n = p.n_rotors
        self._thrusts = scene.add_arrows(
            "/markers/thrusts", np.zeros((n, 2, 3)), np.tile(_THRUST_OK, (n, 1)), shaft_radius=0.01, head_radius=0.025, head_length=0.05
        )
        self._contact = scene.add_arrows(
            "/markers/contact", np.zeros((1, 2, 3)), (142, 68, 173), shaft_radius=0.01, head_radius=0.025, head_length=0.05, visible=False
        )
        self._trail = scene.add_line_segments("/markers/run_trail", np.zeros((1, 2, 3)), (230, 126, 34), thickness=0.006, visible=False)
        self._target = scene.add_transform_controls("/target", scale=0.6 * L, depth_test=False)
        self._target.on_update(self._on_target)

    def _build_gui(self, hover: bool, cog: bool) -> None:
        gui, p = self.server.gui, self.platform
        gui.configure_theme(control_width="large")
        self._sliders = []
        with gui.add_folder("Configuration (FK)"):
            ranges = [(-2.0, 2.0, "m"), (-2.0, 2.0, "m"), (0.0, 3.0, "m"), (-1.5, 1.5, "rad"), (-1.5, 1.5, "rad"), (-math.pi, math.pi, "rad")]
            for j in p.arm:
                if j.kind == "prismatic":
                    lo, hi = (j.lower, j.upper) if math.isfinite(j.lower) and math.isfinite(j.upper) else (-1.0, 1.0)
                    ranges.append((lo, hi, "m"))
                else:
                    lo, hi = (j.lower, j.upper) if math.isfinite(j.lower) and math.isfinite(j.upper) else (-math.pi, math.pi)
                    ranges.append((lo, hi, "rad"))
            for k, (name, (lo, hi, unit)) in enumerate(zip(p.xi_names, ranges)):
                value = float(np.clip(self._xi[k], lo, hi)) if k >= 6 else float(self._xi[k])
                s = gui.add_slider(f"{name} [{unit}]", min=lo, max=hi, step=1e-3 if unit == "m" else 1e-3, initial_value=value)
                s.on_update(self._slider_callback(k))
                self._sliders.append(s)
        with gui.add_folder("End-effector target (IK)"):
            self._hover_box = gui.add_checkbox("hover level", initial_value=bool(hover), hint="level 2: thrust axis vertical (roll = pitch = 0)")
            self._cog_box = gui.add_checkbox("CoG level", initial_value=bool(cog), hint="level 3: CoG on the thrust axis")
            self._orient_box = gui.add_checkbox(
                "match orientation", initial_value=False, hint="level 1: the target's orientation too, not only its position"
            )
            reset = gui.add_button("target to end effector")
            reset.on_click(lambda _: self._move_target_to_ee())
            self._ik_md = gui.add_markdown("IK: drag the target gizmo")
        with gui.add_folder("Hover thrusts"):
            self._hover_md = gui.add_markdown("")
        with gui.add_folder("Run player"):
            self._run_path = gui.add_text("run file (.npz)", initial_value="")
            load = gui.add_button("load run")
            load.on_click(lambda _: self._load_from_gui())
            self._play = gui.add_checkbox("play", initial_value=False)
            self._play.on_update(lambda _: self._on_play())
            self._speed = gui.add_slider("speed", min=0.1, max=4.0, step=0.1, initial_value=1.0)
            self._time = gui.add_slider("time [s]", min=0.0, max=1.0, step=0.01, initial_value=0.0, disabled=True)
            self._time.on_update(lambda _: None if self._syncing else self.show_time(self._time.value))
            self._run_md = gui.add_markdown("no run loaded")

    def _slider_callback(self, k: int):
        def cb(_event) -> None:
            if self._syncing:
                return
            with self._lock:
                self._xi[k] = float(self._sliders[k].value)
                self._apply(move_target=True)

        return cb

    # ------------------------------------------------------------------ state
    @property
    def xi(self) -> np.ndarray:
        """Current thesis coordinates (a copy)."""
        with self._lock:
            return self._xi.copy()

    @property
    def sliders(self) -> dict:
        """The coordinate sliders by name (``"x"`` ... ``"psi"`` and the arm joints): viser GUI handles."""
        return dict(zip(self.platform.xi_names, self._sliders))

    def set_xi(self, xi) -> None:
        """Show the configuration ``xi`` (thesis coordinates); the sliders follow."""
        xi = ch.as_xi(xi, "xi", self.platform.n_xi)
        self.platform.check_arm_limits(xi[6:], "xi[6:]")
        with self._lock:
            self._xi[:] = xi
            self._apply(move_target=True)

    def set_joint(self, name: str, value: float) -> None:
        """Move one coordinate (``"x"``... ``"psi"`` or an arm joint name) as its slider would."""
        names = self.platform.xi_names
        if name not in names:
            raise UnknownNameError("coordinate", name, names)
        xi = self.xi
        xi[names.index(name)] = float(value)
        self.set_xi(xi)

    def solve_target(self, p_world, R_world=None) -> IKResult:
        """Move the target to ``p_world`` (and ``R_world`` when "match orientation" is on or given) and solve the IK.

        Returns the :class:`~qprr.ik.IKResult` the viewer shows; the robot moves to its
        configuration when the IK returned one.
        """
        p_world = as_vector(p_world, 3, "p_world")
        with self._lock:
            if R_world is not None:
                R_world = ch.check_rotation(R_world, "R_world")
                self._orient_box.value = True
            self._target.position = tuple(p_world)
            if R_world is not None:
                self._target.wxyz = _wxyz(R_world)
            return self._solve(p_world, R_world)

    def _on_target(self, event) -> None:
        """Gizmo dragged: solve for the latest pose (drags faster than the IK coalesce)."""
        with self._lock:
            self._pending_target = (np.array(self._target.position, dtype=float), _rotation(self._target.wxyz))
            if self._ik_busy:
                return
            self._ik_busy = True
        try:
            while True:
                with self._lock:
                    pending, self._pending_target = self._pending_target, None
                    if pending is None:
                        self._ik_busy = False
                        return
                    p, R = pending
                    self._solve(p, R if self._orient_box.value else None)
        except BaseException:
            with self._lock:
                self._ik_busy = False
            raise

    def _solve(self, p_world: np.ndarray, R_world: np.ndarray | None) -> IKResult:
        target = pin.SE3(R_world, p_world) if R_world is not None and self._orient_box.value else p_world
        res = ik_solve(self.platform, self._data, target, self._xi, hover=self._hover_box.value, cog=self._cog_box.value)
        self.last_ik = res
        if res.xi is not None:
            self._xi[:] = res.xi
            self._apply(move_target=False)
        self._ik_md.content = _ik_markdown(res, not isinstance(target, np.ndarray), self._hover_box.value, self._cog_box.value)
        return res

    def _move_target_to_ee(self) -> None:
        with self._lock:
            self._apply(move_target=True)

    # ------------------------------------------------------------------ drawing
    def _apply(self, *, move_target: bool, thrusts=None, contact=None) -> None:
        """Display ``self._xi``: robot, sliders, markers, hover thrusts (or the run's ``thrusts``)."""
        p, L = self.platform, self._size
        q = ch.xi_to_q(self._xi)
        self.visualizer.display(q)
        pose = robot_pose(p, self._data, q, self._chain)
        self.pose = pose
        report = hover_report(self._allocator, self._data, q)
        self.hover_state = report
        self._syncing = True
        try:
            for k, s in enumerate(self._sliders):
                v = round(float(self._xi[k]), 9) + 0.0  # shown to 1e-9 (no "-0.000"); self._xi keeps every digit
                if v < s.min:
                    s.min = v
                if v > s.max:
                    s.max = v
                s.value = v
        finally:
            self._syncing = False
        self._cog.position = tuple(pose.com_world)
        a, d = pose.axis_point_world, pose.axis_dir_world
        self._axis.points = np.array([[a - 1.2 * L * d, a + 1.6 * L * d]])
        f = report.f if thrusts is None else np.asarray(thrusts, dtype=float)
        scale = 0.6 * L / (p.total_mass * p.g / p.n_rotors)
        starts = pose.rotor_world
        ends = starts + (np.maximum(f, 0.0) * scale)[:, None] * pose.rotor_axis_world
        self._thrusts.points = np.stack([starts, ends], axis=1)
        self._thrusts.colors = np.array([_thrust_colour(fi, lo, hi) for fi, lo, hi in zip(f, p.thrust_min, p.thrust_max)])
        if contact is not None:
            self._contact.points = np.array([[pose.ee_world, pose.ee_world + scale * np.asarray(contact)]])
            self._contact.visible = True
        else:
            self._contact.visible = False
        if move_target:
            self._target.position = tuple(pose.ee_world)
            self._target.wxyz = _wxyz(pin.updateFramePlacement(p.model, self._data, p.ee_frame).rotation)
        x_cm = cog_offset_body(p, self._data, q)
        self._hover_md.content = _hover_markdown(p, report, x_cm, logged=None if thrusts is None else f)

    # ------------------------------------------------------------------ player
    def load_run(self, run) -> RunLog:
        """Load a run in the player: a :class:`RunLog`, a ``SimResult`` or the path of a result file (:func:`qprr.viz.load_run`)."""
        run = load_run(run) if isinstance(run, (str, os.PathLike)) else as_run(run)
        if run.xi.shape[1] != self.platform.n_xi:
            raise ShapeError(
                f"the run has {run.xi.shape[1]} coordinates per sample (platform {run.platform or '?'!r}); "
                f"{self.platform.name!r} has {self.platform.n_xi}"
            )
        if run.f is not None and run.f.shape[1] != self.platform.n_rotors:
            raise ShapeError(f"the run logs {run.f.shape[1]} thrusts per sample; {self.platform.name!r} has {self.platform.n_rotors} rotors")
        self.stop_playing()  # outside the lock: the player thread may be waiting for it
        with self._lock:
            self.run = run
            stride = max(1, run.n // 2000)
            data = self.platform.data()
            ee = np.array([robot_pose(self.platform, data, ch.xi_to_q(x), self._chain).ee_world for x in run.xi[::stride]])
            if len(ee) >= 2:
                self._trail.points = np.stack([ee[:-1], ee[1:]], axis=1)
                self._trail.visible = True
            self._frame_camera(robot_pose(self.platform, data, ch.xi_to_q(run.xi[0]), self._chain), ee)
            t0, t1 = float(run.t[0]), float(run.t[-1])
            self._syncing = True
            try:
                self._time.min, self._time.max = t0, max(t1, t0 + 1e-3)
                self._time.step = max((t1 - t0) / 1000.0, 1e-3)
                self._time.disabled = False
            finally:
                self._syncing = False
            name = f" of {run.platform}" if run.platform else ""
            self._run_md.content = f"run{name}: {run.n} samples, {t0:g} to {t1:g} s" + (
                "" if run.f is not None else " (no thrusts logged: arrows show hover thrusts)"
            )
            self.show_time(t0)
        return run

    def _frame_camera(self, pose: RobotPose, extra_world) -> None:
        """Aim the camera of new and connected clients at the robot at ``pose`` and the points ``extra_world`` (a run's path)."""
        look_at, position = camera_framing(pose, rotor_radius(self.platform), CAMERA_FOV, extra_world=extra_world)
        self.server.initial_camera.look_at = tuple(look_at)
        self.server.initial_camera.position = tuple(position)
        for client in self.server.get_clients().values():
            client.camera.look_at = tuple(look_at)
            client.camera.position = tuple(position)

    def _load_from_gui(self) -> None:
        try:
            self.load_run(Path(self._run_path.value.strip()))
        except (InputError, ShapeError) as exc:
            self._run_md.content = f"**cannot load**: {exc}"

    def show_time(self, t: float) -> None:
        """Show the loaded run at time ``t`` [s] (the last sample at or before ``t``)."""
        run = self.run
        if run is None:
            raise InputError("no run loaded: call load_run(path) first")
        with self._lock:
            k = int(np.clip(np.searchsorted(run.t, float(t), side="right") - 1, 0, run.n - 1))
            self._run_time = float(run.t[k])
            self._xi[:] = run.xi[k]
            contact = None if run.contact_wrench_world is None else run.contact_wrench_world[k, 0:3]
            self._apply(move_target=True, thrusts=None if run.f is None else run.f[k], contact=contact)
            self._syncing = True
            try:
                self._time.value = min(max(self._run_time, self._time.min), self._time.max)
            finally:
                self._syncing = False

    def _on_play(self) -> None:
        if self._play.value and self.run is not None:
            self._player_stop.clear()
            if self._player_thread is None or not self._player_thread.is_alive():
                self._player_thread = threading.Thread(target=self._player_loop, name="qprr-player", daemon=True)
                self._player_thread.start()
        else:
            self._player_stop.set()

    def _player_loop(self) -> None:
        run, last = self.run, time.perf_counter()
        t = self._run_time if self._run_time < float(run.t[-1]) else float(run.t[0])
        while not self._player_stop.wait(1.0 / 30.0):
            now = time.perf_counter()
            t += (now - last) * float(self._speed.value)
            last = now
            if t > float(run.t[-1]):
                t = float(run.t[0])  # loop
            self.show_time(t)

    def play(self) -> None:
        """Start the player from the shown time (loops at the end; speed from the "speed" slider)."""
        if self.run is None:
            raise InputError("no run loaded: call load_run(path) first")
        self._play.value = True

    @property
    def run_time(self) -> float:
        """Time [s] of the run sample shown by the player."""
        return self._run_time

    def stop_playing(self) -> None:
        """Stop the player (the run stays loaded)."""
        self._player_stop.set()
        thread = self._player_thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=2.0)
        self._player_thread = None
        if self._play.value:
            self._syncing = True
            try:
                self._play.value = False
            finally:
                self._syncing = False

    # ------------------------------------------------------------------ lifetime
    def clients(self) -> int:
        """Number of browser pages connected."""
        return len(self.server.get_clients())

    def close(self) -> None:
        """Stop the player and the server (idempotent)."""
        if self._closed:
            return
        self._closed = True
        self._player_stop.set()
        self.server.stop()

    def serve_forever(self, announce: bool = False) -> None:
        """Block until Ctrl-C (SIGINT) or SIGTERM, then close the server cleanly (``announce``: print the address first)."""
        import signal

        def _stop(signum, frame):
            raise KeyboardInterrupt

        main = threading.current_thread() is threading.main_thread()
        previous = {}
        if main:  # also when SIGINT was inherited as ignored (a background job)
            for sig in (signal.SIGINT, signal.SIGTERM):
                previous[sig] = signal.signal(sig, _stop)
        try:
            if announce:
                print(f"qprr viewer of {self.platform.name}: {self.url}  (Ctrl-C to stop)", flush=True)
            while not self._closed:
                time.sleep(0.2)
        except KeyboardInterrupt:
            print("\nstopping the viewer", file=sys.stderr, flush=True)
        finally:
            self.close()
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# ====================================================================== helpers
CAMERA_FOV = math.radians(50.0)
"""Vertical field of view of the viewer's initial camera [rad]."""
CAMERA_DIRECTION = np.array([1.7, -2.2, 1.3]) / np.linalg.norm([1.7, -2.2, 1.3])
"""Unit vector from the robot towards the initial camera (front right, above), world frame."""


def camera_framing(pose: RobotPose, rotor_r: float, fov: float = CAMERA_FOV, margin: float = 1.15, extra_world=None):
    """(look_at, position) [m, world] of a camera that sees the whole robot at ``pose`` (and the points ``extra_world``,
    (m, 3) [m], e.g. a run's end-effector path).

    The robot's bounding box (rotor centres widened by the rotor radius ``rotor_r``, the arm's joint
    origins, the end effector, the CoG) has a bounding sphere of radius rho about its centre c; a
    camera on :data:`CAMERA_DIRECTION` at distance ``margin`` rho / sin(fov / 2) from c, looking at
    c, holds that sphere in its view for any aspect ratio wider than tall (any platform's size).
    """
    discs = [pose.rotor_world + sign * rotor_r * e for e in np.eye(3) for sign in (1.0, -1.0)]
    extra = np.zeros((0, 3)) if extra_world is None else np.asarray(extra_world, dtype=float).reshape(-1, 3)
    pts = np.vstack([*discs, pose.arm_world, pose.ee_world[None, :], pose.com_world[None, :], extra])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = 0.5 * (lo + hi)
    rho = max(0.5 * float(np.linalg.norm(hi - lo)), 0.05)
    return centre, centre + margin * rho / math.sin(0.5 * fov) * CAMERA_DIRECTION


def _wxyz(R: np.ndarray) -> tuple[float, float, float, float]:
    x, y, z, w = pin.Quaternion(np.asarray(R)).coeffs()
    return (float(w), float(x), float(y), float(z))


def _rotation(wxyz) -> np.ndarray:
    w, x, y, z = (float(c) for c in wxyz)
    return pin.Quaternion(w, x, y, z).normalized().matrix()


def _thrust_colour(f: float, f_min: float, f_max: float) -> np.ndarray:
    """Green inside the bounds, orange within 10 % of a bound, red outside."""
    if f < f_min - 1e-9 or f > f_max + 1e-9:
        return _THRUST_BAD
    span = f_max - f_min if math.isfinite(f_max) else max(f, 1.0)
    if min(f - f_min, f_max - f) < 0.1 * span:
        return _THRUST_LOW
    return _THRUST_OK


def _f(x: float, digits: int) -> str:
    """``x`` with ``digits`` decimals, without a minus sign on a rounded zero."""
    return f"{round(float(x), digits) + 0.0:.{digits}f}"


def _ik_markdown(res: IKResult, pose: bool, hover: bool, cog: bool) -> str:
    levels = ("pose" if pose else "position") + (" > hover" if hover else "") + (" > CoG" if cog else "") + " > posture"
    head = f"**IK {res.status}** ({res.iterations} it, {1000 * res.wall_time:.1f} ms), levels {levels}"
    if res.xi is None:
        return f"{head}  \n{res.reason}"
    lines = [
        head,
        f"position error {res.position_error:.2e} m, orientation error {res.orientation_error:.2e} rad",
        f"CoG offset ({_f(1000 * res.x_cm, 2)}, {_f(1000 * res.y_cm, 2)}) mm, roll {_f(math.degrees(res.roll), 2)} deg, "
        f"pitch {_f(math.degrees(res.pitch), 2)} deg",
    ]
    if not res.success and res.reason:
        lines.append(res.reason)
    return "  \n".join(lines)


def _hover_markdown(platform: Platform, r: HoverReport, x_cm: np.ndarray, logged=None) -> str:
    rows = ["| rotor | hover f [N] | f - f_min | f_max - f |", "|---|---|---|---|"]
    for k in range(platform.n_rotors):
        rows.append(f"| {k + 1} | {_f(r.f[k], 3)} | {_f(r.margin_low[k], 3)} | {_f(r.margin_high[k], 3)} |")
    state = "**can hover**" if r.feasible else f"**cannot hover**: {r.reason}"
    text = f"{state}  \nCoG offset from the thrust axis ({_f(1000 * x_cm[0], 2)}, {_f(1000 * x_cm[1], 2)}) mm\n\n" + "\n".join(rows)
    if logged is not None:
        text += "\n\narrows: logged thrusts [" + ", ".join(f"{v:.2f}" for v in logged) + "] N"
    return text
