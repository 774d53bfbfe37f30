"""FRONT END: ``qprr export px4 | ardupilot`` and ``qprr import px4`` (:mod:`qprr.flightstack`)."""

from __future__ import annotations


def register_cli(sub) -> None:
    """Add the ``export`` and ``import`` command groups to the subparsers ``sub`` of the qprr command line."""
    sub.add_parser("export", help="a platform's rotor geometry for PX4 (.params) or ArduPilot (.lua)")
    sub.add_parser("import", help="a PX4 .params file or the parameters of a ULog as a qprr rotor file")
