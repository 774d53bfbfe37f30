"""FRONT END: ``qprr log show | replay | identify FILE.ulg`` (PX4 flight logs, :mod:`qprr.flightlog`).

Exit codes: 0 done; 1 the log cannot answer (no flight, a topic missing: one line naming it); 2 bad arguments.
"""

from __future__ import annotations

import argparse
import sys

from ..cli.common import PLATFORM_HELP, add_platform_options, fail, integer, output_path, platform_from_args, real
from ..errors import InputError, MissingDependencyError, QprrError, UnknownNameError
from ..model import from_urdf
from .identify import IdentifyOptions, identify
from .phases import find_phases
from .plots import summary_figure
from .record import read_joint_csv, record_from_log
from .replay import replay
from .show import show_lines
from .ulog import FlightLog
from .writeback import write_inertials, write_rotors


def register_flightlog_cli(sub) -> None:
    """Add the ``log`` command group to the subparsers ``sub`` of the qprr command line."""
    p = sub.add_parser("log", help="PX4 flight logs (ULog): show, replay through PX4's mix and a platform, identify the robot")
    group = p.add_subparsers(dest="log_command", required=True, parser_class=type(p))
    _add_show(group)
    _add_replay(group)
    _add_identify(group)


# ------------------------------------------------------------------------------ show
def _add_show(group) -> None:
    p = group.add_parser("show", help="the vehicle, the phases, the topics and rates of a log; a summary figure")
    p.add_argument("log", metavar="FILE.ulg")
    p.add_argument("--plot", default=None, metavar="FILE.png", help="save the summary figure (.png, .pdf or .svg)")
    p.set_defaults(func=_cmd_show)


def _cmd_show(args: argparse.Namespace) -> int:
    prog = "qprr log show"
    try:
        output_path(args.plot, (".png", ".pdf", ".svg"), "plot")
    except ValueError as exc:
        return fail(prog, str(exc))
    try:
        log = FlightLog.read(args.log)
        phases = find_phases(log)
    except (InputError, MissingDependencyError) as exc:
        return fail(prog, str(exc))
    except QprrError as exc:
        return _cannot(prog, exc)
    print("\n".join(show_lines(log, phases)))
    if args.plot:
        fig = summary_figure(log, phases)
        fig.savefig(args.plot, dpi=110)
        print(f"saved {args.plot}")
    return 0


def _cannot(prog: str, exc: Exception) -> int:
    """The log cannot answer (no flight, a missing topic): one line, exit code 1."""
    print(f"{prog}: {exc}", file=sys.stderr)
    return 1


# ------------------------------------------------------------------------------ replay
def _add_replay(group) -> None:
    p = group.add_parser("replay", help="PX4's mix rebuilt from the log's CA_* parameters; the IMU predicted through a platform")
    p.add_argument("log", metavar="FILE.ulg")
    p.add_argument(
        "--platform",
        default=None,
        help="the platform the IMU is predicted through (default: the log's CA_* rotors on a rigid body); " + PLATFORM_HELP,
    )
    add_platform_options(p, name_option=False)
    p.add_argument("--plot", default=None, metavar="FILE.png", help="save the replay figure (.png, .pdf or .svg)")
    p.set_defaults(func=_cmd_replay)


def _cmd_replay(args: argparse.Namespace) -> int:
    prog = "qprr log replay"
    try:
        output_path(args.plot, (".png", ".pdf", ".svg"), "plot")
    except ValueError as exc:
        return fail(prog, str(exc))
    try:
        log = FlightLog.read(args.log)
        custom = args.platform is not None or args.urdf is not None or args.layout is not None
        platform = platform_from_args(args) if custom else None
    except (InputError, MissingDependencyError, UnknownNameError) as exc:
        return fail(prog, str(exc))
    try:
        result = replay(log, find_phases(log), platform)
    except QprrError as exc:
        return _cannot(prog, exc)
    print(result.summary())
    if args.plot:
        result.plot(args.plot)
        print(f"saved {args.plot}")
    return 0


# ------------------------------------------------------------------------------ identify
def _add_identify(group) -> None:
    p = group.add_parser("identify", help="thrust coefficient, hover command, mass, CoG offset, inertia, motor time constant")
    p.add_argument("log", metavar="FILE.ulg")
    known = p.add_mutually_exclusive_group()
    known.add_argument("--mass", type=real(positive=True, unit="kg"), metavar="KG", help="the vehicle's mass: ct is identified")
    known.add_argument("--ct", type=real(positive=True, unit="N"), metavar="N", help="the thrust per rotor at full command: the mass is identified")
    p.add_argument("--joints", metavar="FILE.csv", help="joint angles (header: time, the URDF's joint names)")
    p.add_argument("--urdf", metavar="FILE.urdf", help="the aerial manipulator's URDF (with --rotors and --joints)")
    p.add_argument("--rotors", metavar="FILE.toml", help="its rotor file")
    p.add_argument("--ee-frame", default=None, metavar="NAME", help="its end-effector frame (needed by a URDF without arm joints)")
    p.add_argument("--folds", type=integer(lo=2), default=5, metavar="K", help="cross-validation over K time blocks (default 5)")
    p.add_argument("--json", metavar="FILE.json", help="write every value as {value, std}")
    p.add_argument("--plot", metavar="FILE.png", help="measured against predicted, held-out folds shaded")
    p.add_argument("--write-rotors", metavar="FILE.toml", help="a rotor file with the identified ct as every rotor's f_max")
    p.add_argument("--write-inertials", metavar="FILE.toml", help="the identified inertial values as overrides of --urdf (--inertials)")
    p.set_defaults(func=_cmd_identify)


def _cmd_identify(args: argparse.Namespace) -> int:
    what = "qprr log identify"
    if (args.urdf is None) != (args.rotors is None) or (args.joints is not None and args.urdf is None):
        return fail(what, "--joints needs --urdf and --rotors, and --urdf and --rotors go together")
    if args.write_inertials is not None and args.urdf is None:
        return fail(what, "--write-inertials needs the robot's --urdf and --rotors (the overrides name its links)")
    try:
        options = IdentifyOptions(mass=args.mass, ct=args.ct, folds=args.folds)
        platform = from_urdf(args.urdf, args.rotors, ee_frame=args.ee_frame) if args.urdf is not None else None
        for option, path in (("--write-rotors", args.write_rotors), ("--write-inertials", args.write_inertials)):
            output_path(path, (".toml",), option)
    except (QprrError, ValueError) as exc:
        return fail(what, str(exc))
    try:
        log = FlightLog.read(args.log)
        joints = read_joint_csv(args.joints, platform) if args.joints is not None else None
    except (InputError, MissingDependencyError) as exc:  # the files given: exit 2
        return fail(what, str(exc))
    try:
        record = record_from_log(log, joints)
        result = identify(record, options, platform)
        written = []
        if args.write_rotors:
            written.append(write_rotors(result, args.write_rotors, record, platform))
        if args.write_inertials:
            written.append(write_inertials(result, args.write_inertials, platform))
    except QprrError as exc:  # the log cannot answer (no flight, a missing topic): one line, exit 1
        return _cannot(what, exc)
    print(result.summary())
    for path in written:
        print(f"wrote {path}")
    if args.json:
        print(f"wrote {result.to_json(args.json)}")
    if args.plot:
        print(f"wrote {result.plot(args.plot)}")
    return 0
