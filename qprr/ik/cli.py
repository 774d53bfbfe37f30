"""``qprr ik --target X Y Z [--rpy ROLL PITCH YAW] [--method qp|dls|clika] [platform options] [--json]``, or
``qprr ik --targets FILE.csv [--workers N] [--save OUT.csv]``.

Solves one end-effector target on any platform (:class:`qprr.ik.IKSolver`) and prints the configuration in the thesis
coordinates (names and units from the platform), the status, the errors and, on failure, the solver's reason and what
would help; or every target of a CSV file (columns x, y, z [m], optionally roll, pitch, yaw [rad]; a header line) in
one call (:func:`qprr.ik.batch.solve_many`), printing the summary and writing one row per target with ``--save``.
Exit code 0 when every target is reached in hover, 1 when one is not, 2 on bad arguments.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..cli.common import add_platform_options, fail, integer, platform_from_args, real
from ..errors import InputError, QprrError
from .batch import solve_many
from .solver import METHODS, IKResult, IKSolver

POSITION_COLUMNS = ("x", "y", "z")
"""The columns of a targets file every row fills: the end-effector position in the world [m]."""
ORIENTATION_COLUMNS = ("roll", "pitch", "yaw")
"""Optional columns of a targets file: the end-effector orientation [rad] (fixed axes X, Y, Z), all three or none."""


def _units(platform) -> list[str]:
    """The unit of each thesis coordinate: base position [m], ZYX angles [rad], then each arm joint's."""
    return ["m"] * 3 + ["rad"] * 3 + ["m" if joint.kind == "prismatic" else "rad" for joint in platform.arm]


def advice(platform, result: IKResult, oriented: bool) -> str:
    """What would help after a failed solve, from the status and the platform (empty after a success)."""
    if result.success:
        return ""
    if oriented and not platform.fully_actuated:
        return (
            f"{platform.name} is under-actuated (wrench rank {platform.wrench_rank}): it hovers with its base nearly level, "
            "so the end effector takes only the orientations its arm joints give; give the target without --rpy, or an "
            "orientation the arm's joint axes can produce from a level base"
        )
    if result.status in ("limits", "collision"):
        return "the arm would leave its joint limits or collide there: move the target closer to the base's hover height and in front of the arm"
    if result.status in ("max_iterations", "stalled", "diverged"):
        others = ", ".join(m for m in METHODS if m != result.method)
        return f"the iteration stopped short: try --method {others.split(', ')[0]} (or {others}), or a target nearer the neutral reach"
    return "check the target against `qprr inspect` (the arm's reach and limits)"


def read_targets(path: Path) -> list:
    """The targets of a CSV file (module docstring): positions (3,) [m], or (p, R) pairs where roll, pitch, yaw are given."""
    try:
        text = path.read_text(encoding="utf-8-sig")  # a spreadsheet's byte-order mark is not part of the first column's name
    except OSError as exc:
        raise InputError(f"targets file {str(path)!r} cannot be read: {exc.strerror}") from None
    reader = csv.DictReader(text.splitlines())
    columns = tuple(c.strip() for c in reader.fieldnames or ())
    missing = [c for c in POSITION_COLUMNS if c not in columns]
    if missing:
        raise InputError(f"targets file {str(path)!r}: no column {', '.join(missing)} (a header line x,y,z[,roll,pitch,yaw] is needed)")
    oriented = [c for c in ORIENTATION_COLUMNS if c in columns]
    if oriented and len(oriented) < 3:
        raise InputError(f"targets file {str(path)!r}: give roll, pitch and yaw together or none, got {', '.join(oriented)}")
    targets = []
    for row in reader:
        line = reader.line_num
        if None in row:
            raise InputError(f"targets file {str(path)!r}, line {line}: more values than the header's {len(columns)} columns")
        row = {k.strip(): v for k, v in row.items()}
        try:
            values = [float(row[c]) for c in POSITION_COLUMNS + tuple(oriented)]
        except (TypeError, ValueError):
            raise InputError(f"targets file {str(path)!r}, line {line}: every value must be a number, got {row}") from None
        p_world = np.array(values[:3])
        targets.append(p_world if not oriented else (p_world, pin.rpy.rpyToMatrix(*values[3:])))
    if not targets:
        raise InputError(f"targets file {str(path)!r} has a header and no target")
    return targets


def run_batch(args: argparse.Namespace) -> int:
    """``qprr ik --targets FILE.csv``: every target in one call, the summary printed, the rows written with ``--save``."""
    if args.save and not Path(args.save).parent.is_dir():
        return fail("qprr ik", f"--save {args.save!r}: no folder {str(Path(args.save).parent)!r} to write it in")
    try:
        platform = platform_from_args(args)
        targets = read_targets(Path(args.targets))
        batch = solve_many(IKSolver(platform, args.method), targets, workers=args.workers)
    except QprrError as exc:
        return fail("qprr ik", str(exc))
    print(batch.summary())
    if args.save:
        rows = batch.rows()
        with open(args.save, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=list(rows[0]))
            writer.writeheader()
            writer.writerows(rows)
        print(f"wrote {len(rows)} rows to {args.save}")
    return 0 if batch.success.all() else 1


def run_ik(args: argparse.Namespace) -> int:
    if args.targets is not None:
        if args.rpy is not None or args.json:
            return fail("qprr ik", "--rpy and --json go with one --target; a --targets file gives orientations in its roll, pitch, yaw columns")
        return run_batch(args)
    if args.target is None:
        return fail("qprr ik", "give --target X Y Z (one target) or --targets FILE.csv (many)")
    if args.workers != 1 or args.save is not None:
        return fail("qprr ik", "--workers and --save go with --targets FILE.csv; one --target prints its answer (--json for JSON)")
    try:
        platform = platform_from_args(args)
        p_world = np.array(args.target, dtype=float)
        target = p_world if args.rpy is None else (p_world, pin.rpy.rpyToMatrix(*args.rpy))
        result = IKSolver(platform, args.method).solve(platform.model.createData(), target)
    except QprrError as exc:
        return fail("qprr ik", str(exc))
    help_text = advice(platform, result, args.rpy is not None)
    values = dict(zip(platform.xi_names, result.xi.tolist())) if result.xi is not None else {}
    if args.json:
        report = {"status": str(result.status), "success": result.success, "reason": result.reason, "advice": help_text}
        report |= {"position_error_m": result.position_error, "orientation_error_rad": result.orientation_error, "xi": values}
        print(json.dumps(report, indent=2))
        return 0 if result.success else 1
    print(f"ik on {platform.name}, method {result.method}: {result.status} ({'reached' if result.success else 'not reached'})")
    width = max(map(len, platform.xi_names))
    for (name, value), unit in zip(values.items(), _units(platform)):
        print(f"  {name:>{width}} = {value: .6g} {unit}")
    print(f"  position error {result.position_error:.3g} m, orientation error {result.orientation_error:.3g} rad")
    print(f"  base roll {result.roll:.3g} rad, pitch {result.pitch:.3g} rad; hover feasible: {result.hover_feasible}")
    if not result.success:
        print(f"reason: {result.reason}")
        print(f"what would help: {help_text}")
    return 0 if result.success else 1


def register_ik_cli(sub) -> None:
    """Add the ``ik`` command to the subparsers ``sub`` of the qprr command line."""
    p = sub.add_parser(
        "ik",
        help="solve one end-effector target (or a file of them): configuration, status, and on failure what would help",
        description="Inverse kinematics of one target on any platform (qprr.ik.IKSolver): the end effector at --target "
        "(world, m), optionally with the orientation --rpy (roll, pitch, yaw in rad, fixed axes X, Y, Z) while hovering; "
        "or every target of a CSV file (--targets: columns x, y, z and optionally roll, pitch, yaw) in one call.",
    )
    which = p.add_mutually_exclusive_group()
    which.add_argument("--target", type=real(unit="m"), nargs=3, default=None, metavar=("X", "Y", "Z"), help="end-effector position in the world [m]")
    which.add_argument(
        "--targets", default=None, metavar="FILE.csv", help="many targets: a CSV file with columns x, y, z [m] and optionally roll, pitch, yaw [rad]"
    )
    p.add_argument("--rpy", type=real(unit="rad"), nargs=3, default=None, metavar=("ROLL", "PITCH", "YAW"), help="end-effector orientation [rad]")
    p.add_argument("--method", choices=METHODS, default="qp", help="qp (task priorities, default), dls or clika")
    add_platform_options(p)
    p.add_argument("--json", action="store_true", help="print the result as JSON (one --target)")
    p.add_argument("--workers", type=integer(lo=1), default=1, help="with --targets: processes solving them (default 1)")
    p.add_argument("--save", default=None, metavar="OUT.csv", help="with --targets: one row per target (status, errors, configuration)")
    p.set_defaults(func=run_ik)
