"""``qprr wheeled NAME [--plot FILE.png]``: run a robot or an exercise of the mobile-robots lecture."""

from __future__ import annotations

import argparse
import sys

from ..errors import MissingDependencyError, QprrError


def _cmd_wheeled(args: argparse.Namespace) -> int:
    from .demos import catalogue, run_demo

    names = catalogue()
    if args.name not in names:
        print(f"qprr wheeled: error: unknown robot or exercise {args.name!r}; valid: {', '.join(names)}", file=sys.stderr)
        return 2
    from ..cli.common import fail, output_path

    try:
        output_path(args.plot, (".png", ".pdf", ".svg"), "plot")
    except ValueError as exc:
        return fail("qprr wheeled", str(exc))
    try:
        demo = run_demo(args.name)
    except MissingDependencyError as err:
        print(f"qprr wheeled: error: {err}", file=sys.stderr)
        return 2
    except QprrError as err:
        print(f"qprr wheeled: {type(err).__name__}: {err}", file=sys.stderr)
        return 1
    print("\n".join(demo.lines))
    if args.plot is not None:
        try:
            print(f"figure {demo.plot(args.plot)}")
        except OSError as err:
            return fail("qprr wheeled", f"cannot write {args.plot!r}: {err.strerror or err}")
    return 0 if demo.ok else 1


def register_wheeled_cli(subparsers) -> None:
    """Add ``wheeled`` to the ``qprr`` command line."""
    from .demos import catalogue

    lines = [f"  {n:24s} {d}" for n, d in catalogue().items()]
    p = subparsers.add_parser(
        "wheeled",
        help="wheeled mobile robots of the lecture: robots, exercises, control, mobile manipulation",
        description="Run a robot or an exercise of the mobile-robots lecture (prints the checks; optional figure).\n\n"
        "robots and exercises:\n" + "\n".join(lines),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("name", metavar="ROBOT-OR-EXERCISE", help="one of the names listed above")
    p.add_argument("--plot", default=None, metavar="FILE.png", help="save the figure to FILE.png")
    p.set_defaults(func=_cmd_wheeled)
