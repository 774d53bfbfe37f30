"""FRONT END: ``qprr export px4 | ardupilot`` and ``qprr import px4`` (:mod:`qprr.flightstack`).

``qprr export px4 [platform options] [--pose v1,v2,...] -o FILE.params [--mixer-map FILE.png]``: PX4's ``CA_*``
geometry at the arm pose, printed, written for QGroundControl, with the fixed mixer's error over the arm's range.
``qprr export ardupilot [platform options] [--pose ...] -o FILE.lua [--dynamic]``: an ArduPilot Lua frame script.
``qprr import px4 FILE.params|FILE.ulg -o FILE.toml [--mass KG]``: a qprr rotor file from PX4's parameters, with
every check a rotor file gets (the hover check needs the vehicle's mass: without ``--mass`` it is skipped, and said).

Exit codes: 0 done; 2 bad arguments or a refused geometry (one line naming the option, the value and the fix).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from ..cli.common import Parser, add_platform_options, fail, integer, output_path, platform_from_args, real, reals
from ..errors import InputError
from ..flightlog.ulog import FlightLog
from ..rotors import check_rotor_set, rotors_to_toml
from ..version import __version__
from .ardupilot import dynamic_script, frame_script, write_script
from .mixer import mixer_error
from .px4 import (
    AIRFRAME_MULTIROTOR,
    STANDARD_GRAVITY,
    Px4Geometry,
    check_geometry,
    geometry_from_platform,
    read_params,
    rotors_from_geometry,
    write_params,
)


def ulog_parameters(path: Path) -> dict:
    """The parameters stored in a ULog file, read by the one ULog reader (:class:`qprr.flightlog.ulog.FlightLog`;
    needs the ``flightlog`` extra, pyulog)."""
    return dict(FlightLog.read(path).parameters)


PARAMETER_READERS = {".params": read_params, ".ulg": ulog_parameters}
"""File suffix -> the function reading PX4 parameters (name -> value) from such a file (``qprr import px4``)."""


def _pose(args: argparse.Namespace, platform) -> np.ndarray | None:
    """``--pose`` checked against the platform's arm (count and limits); None: the neutral pose."""
    if args.pose is None:
        return None
    if len(args.pose) != platform.n_arm:
        joints = ", ".join(platform.arm_names) or "none"
        raise InputError(f"--pose {','.join(map(str, args.pose))}: {platform.name} has {platform.n_arm} arm joints ({joints}), give one value each")
    try:
        return platform.check_arm_limits(args.pose, "--pose")
    except InputError as exc:
        raise InputError(f"{exc} (revolute joints in rad, prismatic in m)") from None


def _cmd_export_px4(args: argparse.Namespace) -> int:
    prog = "qprr export px4"
    try:
        out = output_path(args.output, (".params",), "output")
        figure = output_path(args.mixer_map, (".png", ".pdf", ".svg"), "mixer-map")
    except ValueError as exc:
        return fail(prog, str(exc))
    platform = platform_from_args(args)
    q_arm = _pose(args, platform)
    t0 = time.perf_counter()
    geometry = geometry_from_platform(platform, q_arm)
    pose = "neutral" if q_arm is None else np.round(q_arm, 6).tolist()
    print(geometry.summary())
    header = [f"qprr {__version__}", f"platform {platform.name}", f"arm pose {pose} ({', '.join(platform.arm_names) or 'no arm'})"]
    write_params(geometry, out, header=header)
    print(f"saved {out} ({len(geometry.parameters())} parameters)")
    if platform.n_arm:
        res = mixer_error(platform, q_arm, joints=args.joints, resolution=args.resolution)
        print(res.summary())
        if figure is not None:
            res.plot(figure)
            print(f"saved {figure}")
    elif figure is not None:
        return fail(prog, f"--mixer-map {args.mixer_map!r}: {platform.name} has no arm, its mixer does not change")
    print(f"export px4: {time.perf_counter() - t0:.2f} s")
    return 0


def _cmd_export_ardupilot(args: argparse.Namespace) -> int:
    prog = "qprr export ardupilot"
    try:
        out = output_path(args.output, (".lua",), "output")
    except ValueError as exc:
        return fail(prog, str(exc))
    platform = platform_from_args(args)
    q_arm = _pose(args, platform)
    if args.dynamic and platform.n_arm == 0:
        return fail(prog, f"--dynamic: {platform.name} has no arm; leave out --dynamic for a fixed frame")
    text = dynamic_script(platform, q_arm, joints=args.joints, resolution=args.resolution) if args.dynamic else frame_script(platform, q_arm)
    write_script(text, out)
    kind = "Motors_dynamic table" if args.dynamic else "Motors_6DoF frame" if "Motors_6DoF" in text else "MotorsMatrix frame"
    print(f"saved {out}: ArduPilot {kind} for {platform.name}")
    return 0


def _cmd_import_px4(args: argparse.Namespace) -> int:
    prog = "qprr import px4"
    source = Path(args.file)
    reader = PARAMETER_READERS.get(source.suffix.lower())
    if reader is None:
        return fail(prog, f"{args.file!r}: give a QGroundControl parameter file (.params) or a PX4 flight log (.ulg)")
    if not source.is_file():
        return fail(prog, f"{args.file!r} does not exist (or is not a file)")
    try:
        out = output_path(args.output, (".toml",), "output")
    except ValueError as exc:
        return fail(prog, str(exc))
    geometry = Px4Geometry.from_parameters(reader(source))
    if geometry.airframe != AIRFRAME_MULTIROTOR:
        return fail(prog, f"{args.file}: CA_AIRFRAME = {geometry.airframe}, not a multirotor (0): qprr's platforms are multirotors")
    check_geometry(geometry, source=str(source))
    rotors = rotors_from_geometry(geometry)
    weight = 0.0 if args.mass is None else args.mass * STANDARD_GRAVITY
    check_rotor_set(rotors, weight, (0.0, 0.0, 0.0), source=str(source), hover=args.mass is not None)
    header = [
        f"rotor file written by qprr {__version__} (qprr import px4) from {source.name}",
        "positions [m] relative to the centre of gravity, in qprr's body frame B (x forward, y left, z up)",
        "f_max = CA_ROTOR{i}_CT (thrust at full command), kappa = |KM|, spin = -sign(KM)",
    ]
    out.write_text(rotors_to_toml(rotors, header), encoding="utf-8")
    print(f"{geometry.n} rotors from {source}: rank {np.linalg.matrix_rank(geometry.effectiveness())} effectiveness, checks passed")
    if args.mass is None:
        print("hover check skipped: no --mass given (the parameters carry no vehicle mass)")
    else:
        print(f"hover check passed for {args.mass:g} kg")
    print(f"saved {out}")
    return 0


def _add_export(sub) -> None:
    p = sub.add_parser("export", help="a platform's rotor geometry for PX4 (.params) or ArduPilot (.lua)")
    group = p.add_subparsers(dest="stack", required=True, parser_class=Parser)
    px = group.add_parser(
        "px4",
        help="PX4's CA_* parameters at an arm pose (a QGroundControl .params file) and the fixed mixer's error",
        description="PX4's control-allocation geometry (CA_AIRFRAME, CA_ROTOR_COUNT, CA_ROTOR{i}_PX/PY/PZ/AX/AY/AZ/CT/KM, "
        "FRD, positions relative to the centre of gravity at --pose) and how wrong that fixed mixer becomes as the arm moves.",
    )
    ap = group.add_parser("ardupilot", help="an ArduPilot Lua frame script (MotorsMatrix, Motors_6DoF, or Motors_dynamic with --dynamic)")
    for q in (px, ap):
        add_platform_options(q)
        q.add_argument("--pose", type=reals(), default=None, metavar="V1,V2,...", help="arm joint values [rad or m] (default: neutral)")
        q.add_argument(
            "--joints",
            type=lambda s: [x for x in s.split(",") if x],
            default=None,
            metavar="J1[,J2]",
            help="names of the one or two arm joints of the map or table (default: the first two)",
        )
        q.add_argument("--resolution", type=integer(lo=2, hi=201), default=None, metavar="N", help="grid points per joint (px4: 41, ardupilot: 9)")
    px.add_argument("-o", "--output", required=True, metavar="FILE.params", help="the parameter file to write")
    px.add_argument("--mixer-map", default=None, metavar="FILE.png", help="save the fixed mixer's error map")
    px.set_defaults(func=_cmd_export_px4, resolution=41)
    ap.add_argument("-o", "--output", required=True, metavar="FILE.lua", help="the Lua script to write")
    ap.add_argument("--dynamic", action="store_true", help="a Motors_dynamic script whose factors follow the arm joints")
    ap.set_defaults(func=_cmd_export_ardupilot, resolution=9)


def _add_import(sub) -> None:
    p = sub.add_parser("import", help="a PX4 .params file or the parameters of a ULog as a qprr rotor file")
    group = p.add_subparsers(dest="stack", required=True, parser_class=Parser)
    px = group.add_parser("px4", help="CA_* parameters (.params or .ulg) to a qprr rotor file (.toml), every rotor-file check applied")
    px.add_argument("file", metavar="FILE.params|FILE.ulg")
    px.add_argument("-o", "--output", required=True, metavar="FILE.toml", help="the rotor file to write")
    px.add_argument("--mass", type=real(positive=True, unit="kg"), default=None, help="vehicle mass [kg] for the hover check (without: skipped)")
    px.set_defaults(func=_cmd_import_px4)


def register_flightstack_cli(sub) -> None:
    """Add the ``export`` and ``import`` command groups to the subparsers ``sub`` of the qprr command line."""
    _add_export(sub)
    _add_import(sub)
