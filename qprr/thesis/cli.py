"""The thesis plug-in's command group: ``qprr urdf`` (regenerate the Q-PRR's URDF from the thesis parameters).

Added to the ``qprr`` parser through the registry :data:`qprr.registry.COMMANDS` (:func:`qprr.thesis.register`);
``qprr compare`` and ``qprr check`` are the core's commands, over the comparisons and checks the thesis registers.
"""

from __future__ import annotations

import argparse

from ..cli.common import fail, output_path


def _cmd_urdf(args: argparse.Namespace) -> int:
    from .urdf import URDF_PATH, write_urdf

    try:
        out = output_path(args.output, (".urdf",), "output") if args.output else URDF_PATH
    except ValueError as exc:
        return fail("qprr urdf", str(exc))
    print(write_urdf(out))
    return 0


def register_cli(sub) -> None:
    """Add ``urdf`` to the subparsers ``sub`` of the ``qprr`` command."""
    p = sub.add_parser("urdf", help="regenerate urdf/qprr.urdf from the thesis parameters")
    p.add_argument("-o", "--output", default=None, help="output path (default: the packaged urdf/qprr.urdf)")
    p.set_defaults(func=_cmd_urdf)
