"""Command-line entry points of :mod:`qprr.viz`: ``qprr view`` and ``qprr animate``, and the call behind ``--animate``.

:func:`register_viz_cli` adds the two subcommands to ``qprr``'s parser (it imports neither viser nor
matplotlib: they load when a command runs).  :func:`animate_to_file` is what a command with an
``--animate FILE`` option calls after a run.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def animate_to_file(platform, result, path: str | Path, *, progress: bool = True, **options):
    """Animate ``result`` (a ``SimResult`` or :class:`~qprr.viz.run.RunLog`) of ``platform`` to ``path``
    (``.gif`` or ``.mp4``) with a progress bar, print where it went and how long it took; returns the
    :class:`~qprr.viz.animation.AnimationInfo`."""
    from .animation import animate_result

    info = animate_result(platform, result, path, progress=progress, **options)
    print(
        f"animation: {info.path} ({info.frames} frames at {info.fps:g} fps for {info.duration:.1f} s of run, "
        f"{info.writer}, written in {info.wall_time:.1f} s)"
    )
    return info


def demo_run(platform, duration: float = 30.0, rate: float = 20.0):
    """A :class:`~qprr.viz.run.RunLog` to look at without a simulator: the IK path of an end effector
    circling 0.3 m around the neutral end-effector position of a platform hovering 1 m up while its
    tool pitches by +-0.9 rad (period 10 s), ``rate`` samples per second, hover thrusts logged."""
    from ..charts import rot_y, xi_to_q
    from ..kinematics import ee_placement
    from .ikpath import ik_path

    xi0 = platform.neutral_xi()
    xi0[2] = 1.0
    M0 = ee_placement(platform, platform.data(), xi_to_q(xi0))
    t = np.arange(int(round(duration * rate)) + 1) / rate
    w = 2.0 * np.pi * t
    p = M0.translation + np.stack([0.3 * np.cos(w / 15.0) - 0.3, 0.3 * np.sin(w / 15.0), 0.1 * np.sin(w / 10.0)], axis=1)
    R = np.array([M0.rotation @ rot_y(0.9 * np.sin(a / 10.0)) for a in w])
    return ik_path(platform, t, p, R, xi0=xi0).run


def check_run_platform(run, platform, path) -> None:
    """A run file drawn on another platform than the one it was recorded on is refused (InputError naming both)."""
    from ..errors import InputError

    if run.platform and run.platform != platform.name:
        raise InputError(
            f"run {str(path)!r} was recorded on platform {run.platform!r}, not on {platform.name!r}: name its platform "
            "(--platform NAME [--layout plus|x], or --urdf FILE --rotors FILE.toml for your own)"
        )


def _cmd_view(args: argparse.Namespace) -> int:
    from ..cli.common import platform_from_args
    from ..errors import QprrError

    try:
        from .viewer import Viewer

        platform = platform_from_args(args)
        if args.run is not None:
            from .run import load_run

            check_run_platform(load_run(args.run), platform, args.run)
        viewer = Viewer(platform, port=args.port, run=args.run, hover=not args.no_hover, cog=not args.no_cog, verbose=False)
    except QprrError as exc:
        print(f"qprr view: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    if args.open:
        import webbrowser

        webbrowser.open(viewer.url)
    viewer.serve_forever(announce=True)  # the address is printed once Ctrl-C is handled
    return 0


def _cmd_animate(args: argparse.Namespace) -> int:
    from ..cli.common import fail, output_path, platform_from_args
    from ..errors import QprrError

    try:
        output_path(args.output, (".gif", ".mp4"), "output")
    except ValueError as exc:
        return fail("qprr animate", str(exc))
    try:
        from .run import load_run

        platform = platform_from_args(args)
        if args.run is None:
            print(f"no run given: animating the demo IK path of {platform.name} ({args.duration:g} s)")
            run = demo_run(platform, args.duration)
        else:
            run = load_run(args.run)
            check_run_platform(run, platform, args.run)
        animate_to_file(platform, run, args.output, fps=args.fps, speed=args.speed, view=args.view, size=tuple(args.size), progress=not args.quiet)
    except QprrError as exc:
        print(f"qprr animate: error: {exc}", file=sys.stderr)
        return 2
    return 0


def register_viz_cli(sub) -> None:
    """Add ``view`` and ``animate`` to the subparsers ``sub`` of the ``qprr`` command."""
    from ..cli.common import PLATFORM_HELP, add_platform_options, integer, real

    p = sub.add_parser(
        "view",
        help="interactive 3-D viewer in the browser (127.0.0.1): joint sliders, IK target, hover thrusts, run player",
        description="Start the viewer (needs: pip install 'qprr[viewer]'); Ctrl-C stops it.",
    )
    p.add_argument("platform", nargs="?", default=None, help=PLATFORM_HELP)
    add_platform_options(p, name_option=False)
    p.add_argument("--port", type=integer(lo=0, hi=65535), default=8080, help="TCP port on 127.0.0.1 (default 8080; 0: any free port)")
    p.add_argument("--run", default=None, metavar="FILE.npz", help="load a saved run in the player")
    p.add_argument("--no-hover", action="store_true", help="start with the IK's hover level off")
    p.add_argument("--no-cog", action="store_true", help="start with the IK's CoG level off")
    p.add_argument("--open", action="store_true", help="open the page in the default browser")
    p.set_defaults(func=_cmd_view)

    p = sub.add_parser(
        "animate",
        help="3-D animation of a saved run (or of a demo IK path) to GIF or MP4, headless",
        description="Animate a result file (written by qprr simulate NAME --save RUN.npz); without RUN, a 30 s demo IK path.",
    )
    p.add_argument("run", nargs="?", default=None, metavar="RUN.npz", help="the run (default: the demo IK path)")
    p.add_argument("-o", "--output", default="animation.gif", help="output .gif (Pillow) or .mp4 (ffmpeg), folder must exist; default animation.gif")
    add_platform_options(p)
    p.add_argument("--fps", type=real(positive=True), default=20.0, help="frames per second (default 20)")
    p.add_argument("--speed", type=real(positive=True), default=1.0, help="run seconds per video second (default 1)")
    p.add_argument("--view", choices=("follow", "fixed"), default="follow", help="camera: follow the base (default) or the whole run")
    p.add_argument("--size", type=integer(lo=1), nargs=2, default=(640, 480), metavar=("W", "H"), help="pixels (default 640 480)")
    p.add_argument("--duration", type=real(positive=True, unit="s"), default=30.0, help="length of the demo IK path [s] (default 30)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_animate)
