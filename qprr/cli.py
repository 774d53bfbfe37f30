"""Command line: ``qprr check | urdf | simulate | compare | wheeled``."""

from __future__ import annotations

import argparse
import sys


def _cmd_check(args: argparse.Namespace) -> int:
    from .checks import main as check_main

    return check_main(verbose=args.verbose)


def _cmd_urdf(args: argparse.Namespace) -> int:
    from .urdf import URDF_PATH, write_urdf

    print(write_urdf(args.output or URDF_PATH))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="qprr", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("check", help="check the model against the thesis's closed forms (table of verdicts)")
    p.add_argument("-v", "--verbose", action="store_true", help="print the evidence behind each verdict")
    p.set_defaults(func=_cmd_check)
    p = sub.add_parser("urdf", help="regenerate urdf/qprr.urdf from the parameters")
    p.add_argument("-o", "--output", default=None, help="output path (default: the packaged urdf/qprr.urdf)")
    p.set_defaults(func=_cmd_urdf)
    try:  # simulation commands are registered by qprr.scenarios when it is present
        from .scenarios import register_cli
    except ImportError:
        pass
    else:
        register_cli(sub)
    try:  # wheeled robots are registered by qprr.wheeled when it is present
        from .wheeled.cli import register_cli as register_wheeled
    except ImportError:
        pass
    else:
        register_wheeled(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return int(args.func(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
