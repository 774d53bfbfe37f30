"""``qprr analyze workspace|cog|singularity|hover|capacity|opspace [--platform NAME] [--plot FILE.png]``.

Registered into :mod:`qprr.cli` by :func:`register_analysis_cli`.  ``--platform`` takes a named platform
(:data:`qprr.platforms.NAMES`) or a name of the thesis nomenclature (2.1) that
:func:`qprr.build` makes (``HEX-RRR``, ``QX-PRR``...); ``--urdf FILE --rotors FILE.toml
[--ee-frame NAME]`` a user's own platform.  Published numbers for a platform (the thesis's
(4.46)-(4.48) on the Q-PRR's singularity map) come from the providers of the registry
:data:`qprr.registry.MAP_REFERENCES`, filled by plug-ins: the maps never import them.
"""

from __future__ import annotations

import argparse
import time

from ..platforms import DEFAULT_PLATFORM
from ..progress import FractionProgress
from ._common import MapReference
from .budget import DEFAULT_BUDGET

MAPS = ("workspace", "cog", "singularity", "hover", "capacity", "opspace")
COLLISION = {"auto": None, "on": True, "off": False}
"""``--collision`` to the maps' ``collision`` option (auto: check when the platform has a collision model)."""
COLLISION_MAPS = ("workspace", "hover")
"""The maps that measure a collision-free part (their ``collision`` option); the others sample the joint box only."""


def resolve_platform(name: str):
    """A platform from a registry name (``qprr.load``) or a (2.1) designation (``qprr.build``): :func:`qprr.platforms.resolve`."""
    from qprr.platforms import resolve

    return resolve(name)


def map_reference(map_name: str, platform, result) -> MapReference | None:
    """The first reference a provider of :data:`qprr.registry.MAP_REFERENCES` gives for this map and platform, or None."""
    from ..errors import UnknownNameError
    from ..model import check_platform
    from ..registry import MAP_REFERENCES

    if map_name not in MAPS:
        raise UnknownNameError("map", map_name, MAPS)
    check_platform(platform)
    for provider in MAP_REFERENCES.values():
        ref = provider(map_name, platform, result)
        if ref is not None:
            return ref
    return None


def run_analyze(args: argparse.Namespace) -> int:
    from ..cli.common import fail, output_path, platform_from_args

    try:
        output_path(args.plot, (".png", ".pdf", ".svg"), "plot")
    except ValueError as exc:
        return fail("qprr analyze", str(exc))
    if args.collision != "auto" and args.map not in COLLISION_MAPS:
        return fail(
            "qprr analyze",
            f"--collision {args.collision} does not apply to the {args.map} map: it samples the whole joint box and "
            f"measures no collision-free part; the maps that do: {', '.join(COLLISION_MAPS)} (leave --collision out here)",
        )
    platform = platform_from_args(args)
    progress = FractionProgress(quiet=args.quiet)  # stderr: a bar on a terminal, plain lines in a log
    t0 = time.perf_counter()
    try:
        res, extra = _compute(args, platform, _sizing(args), progress)
    finally:
        progress.close()
    seconds = time.perf_counter() - t0
    fig = _report(args, res, extra, platform)
    if args.samples:
        print(f"  --samples {args.samples} given: --budget not used")
    budget = f" (budget {args.budget:g} s: pilots and map; the figure not included)" if not args.samples else ""
    print(f"{args.map} map of {platform.name}: {seconds:.2f} s{budget}")
    if fig is not None:
        fig.savefig(args.plot, dpi=120)
        print(f"saved {args.plot}")
    return 0


def _sizing(args: argparse.Namespace) -> dict:
    """The sample-count settings of every map's options: ``--samples N`` (no budget), else ``--budget`` seconds
    timed with :func:`time.perf_counter` (the one clock the maps read, passed from here)."""
    if args.samples:
        return {"n_samples": args.samples, "budget": None}
    return {"budget": args.budget, "clock": time.perf_counter}


def _halved(sizing: dict) -> dict:
    """``sizing`` for one of two maps sharing a budget (the CoG regions and the balance map)."""
    return {**sizing, "budget": sizing["budget"] / 2.0} if sizing["budget"] is not None else sizing


def _compute(args: argparse.Namespace, platform, sizing: dict, progress: FractionProgress):
    """The map ``args.map`` of ``platform`` (``sizing``: :func:`_sizing`): (result, the balance map of ``cog`` or None)."""
    from .capacity import capacity
    from .cog import balance, cog_regions
    from .hover import hover
    from .opspace import opspace_map
    from .singularity import singularity
    from .workspace import workspace

    if args.map == "workspace":
        return workspace(platform, progress=progress, collision=COLLISION[args.collision], **sizing), None
    if args.map == "cog":
        masses = args.payload if args.payload else [0.0, 0.5]
        res = cog_regions(platform, payload_masses=masses, progress=progress, **_halved(sizing))
        return res, balance(platform, tol=args.tol, progress=progress, **_halved(sizing))
    if args.map == "singularity":
        return singularity(platform, task=args.task, progress=progress, **sizing), None
    if args.map == "hover":
        masses = args.payload if args.payload else [0.0, 0.25, 0.5, 1.0, 1.5, 2.0]
        collision = COLLISION[args.collision]
        return hover(platform, payload_masses=masses, torque_reserve=args.reserve, progress=progress, collision=collision, **sizing), None
    if args.map == "capacity":
        return capacity(platform, torque_reserve=args.reserve, progress=progress, **sizing), None
    return opspace_map(platform, progress=progress, **sizing), None


def _report(args: argparse.Namespace, res, extra, platform):
    """Print the summary of the map ``res`` (and ``extra``: the balance map of ``cog``); its figure when ``--plot``."""
    from . import plots

    print(res.summary())
    if extra is not None:
        print(extra.summary())
    ref = map_reference(args.map, platform, res) if args.map == "singularity" else None
    if ref is not None:
        print("\n".join(ref.lines))
    if not args.plot:
        return None
    if args.map == "hover":
        return _hover_figures(res, args.plot)
    figures = {
        "workspace": lambda: plots.workspace_figure(res),
        "cog": lambda: plots.cog_figure(res, extra),
        "singularity": lambda: plots.singularity_figure(res, ref.curves if ref is not None else None),
        "capacity": lambda: plots.capacity_figure(res),
        "opspace": lambda: plots.opspace_figure(res),
    }
    return figures[args.map]()


def _hover_figures(res, path: str):
    """The hover figure; the wrench-set sections saved beside ``path`` for a fully actuated platform."""
    from . import plots

    if res.wrench_set.rank == 6:
        stem = path.rsplit(".", 1)
        side = f"{stem[0]}-wrench-set.{stem[1] if len(stem) > 1 else 'png'}"
        plots.wrench_set_figure(res).savefig(side, dpi=120)
        print(f"saved {side}")
    return plots.hover_figure(res)


def register_analysis_cli(sub) -> None:
    """Add the ``analyze`` command to the subparsers ``sub`` of the qprr command line."""
    from ..cli.common import add_platform_options, integer, real, reals

    p = sub.add_parser(
        "analyze",
        help="design maps: workspace, CoG, singularities, hover, payload capacity, operational space",
        description="Design maps of a platform: reachable workspace (with and without the slider), CoG balance, "
        "singularities, hover feasibility and thrust margins, payload capacity, operational-space inertia. "
        f"--platform takes a named platform ({DEFAULT_PLATFORM}, borinot_flying_arm_2, hextilt_flying_arm_5, a plug-in's) or a "
        "designation of the thesis nomenclature (2.1) such as HEX-RRR or QX-PRR; --urdf FILE --rotors "
        "FILE.toml your own platform (docs/platforms.md).",
    )
    p.add_argument("map", choices=MAPS, help="which map")
    add_platform_options(p)
    p.add_argument("--plot", default=None, metavar="FILE.png", help="save the figure")
    p.add_argument(
        "--budget",
        type=real(positive=True, unit="s"),
        default=DEFAULT_BUDGET,
        metavar="SECONDS",
        help=f"wall time the map may take (default {DEFAULT_BUDGET:g} s): pilot batches time the map on this platform and "
        "machine, and the joint-grid size (values per joint from the arm's joint count) is the largest that fits; the "
        "summary says the count chosen and the error bars reached",
    )
    p.add_argument("--samples", type=integer(lo=1), default=None, help="joint-grid size, instead of the budget (the budget is then not used)")
    p.add_argument("--payload", type=reals(nonnegative=True, unit="kg"), default=None, help="payload masses in kg, comma-separated (cog, hover)")
    p.add_argument("--reserve", type=real(nonnegative=True, unit="N m"), default=0.0, help="torque reserve about every axis [N m] (hover, capacity)")
    p.add_argument("--task", default="pose", choices=("pose", "position"), help="task rows of the singularity map")
    p.add_argument(
        "--collision",
        choices=tuple(COLLISION),
        default="auto",
        help="also measure the collision-free part (workspace, hover): auto (default) when the platform has a collision model "
        "(its URDF's <collision> geometry), on (required), off. On the Q-PRR's default workspace (1e6 configurations per "
        "region) the check and the collision-free measures add about 40%% to the time (about 3.8 s instead of about 2.8 s "
        "on an idle 2-core machine, docs/analysis.md#speed): the default keeps them because the reachable workspace without self-collision "
        "is 27%% smaller than the joint box's image, the number a design is judged by",
    )
    p.add_argument("--tol", type=real(nonnegative=True, unit="m"), default=1e-6, help="CoG offset counted as balanced [m] (cog)")
    p.add_argument(
        "-q", "--quiet", action="store_true", help="no progress on stderr (shown by default: a bar on a terminal, a line every few seconds in a log)"
    )
    p.set_defaults(func=run_analyze)
    register_inspect(sub)


def run_inspect(args: argparse.Namespace) -> int:
    """``qprr inspect``: the platform's report (:func:`qprr.analysis.inspect.inspect_platform`)."""
    from ..cli.common import platform_from_args
    from .inspect import inspect_platform

    print(inspect_platform(platform_from_args(args)).text())
    return 0


def register_inspect(sub) -> None:
    """Add the ``inspect`` command: a platform's tree, inertias, joints, rotors, actuation and notes."""
    from ..cli.common import add_platform_options

    p = sub.add_parser(
        "inspect",
        help="print a platform: tree, masses, inertias, joint limits, rotors, actuation summary, notes",
        description="Print what a platform is: its kinematic tree, the mass, CoM and principal moments of each body, the "
        "arm's limits, efforts, damping and friction, the rotor table, what the rotors can do at the neutral pose (wrench "
        "rank, producible directions, hover thrusts and margin) and notes (thrust-to-weight, CoG offset from the rotor "
        "axis, the friction's stiffness). --platform NAME, a (2.1) designation such as HEX-RRR, or --urdf FILE --rotors "
        "FILE.toml for your own.",
    )
    add_platform_options(p)
    p.set_defaults(func=run_inspect)
