"""Command line: ``qprr simulate | compare | check`` and the command groups of :mod:`qprr.viz`,
:mod:`qprr.analysis`, :mod:`qprr.campaign`, :mod:`qprr.wheeled` and of plug-ins (:data:`qprr.registry.COMMANDS`:
the thesis adds ``qprr urdf``).

``compare`` runs the comparisons of :data:`qprr.registry.COMPARISONS` and ``check`` the suites of
:data:`qprr.registry.CHECKS`; this module imports no plug-in (the thesis's arrive through the registries).
Errors in the arguments end in one line on stderr and exit code 2; a run that diverges prints
its error and exit code 1; otherwise 0.
"""

from __future__ import annotations

import argparse
import sys
import time
from importlib import import_module
from pathlib import Path

from ..errors import QprrError
from ..platforms import DEFAULT_PLATFORM
from ..registry import CHECKS, COMMANDS, COMPARISONS
from ..sim.integrators import INTEGRATORS
from ..version import __version__
from .common import Parser, add_platform_options, cache_dir, fail, integer, option_value, output_path, platform_from_args, real

GROUP_COMMANDS = {
    "view": "qprr.viz.cli:register_viz_cli",
    "animate": "qprr.viz.cli:register_viz_cli",
    "wheeled": "qprr.wheeled.cli:register_wheeled_cli",
    "analyze": "qprr.analysis.cli:register_analysis_cli",
    "inspect": "qprr.analysis.cli:register_analysis_cli",
    "ik": "qprr.ik.cli:register_ik_cli",
    "campaign": "qprr.campaign.cli:register_campaign_cli",
    "design": "qprr.design.cli:register_design_cli",
    "export": "qprr.flightstack.cli:register_flightstack_cli",
    "import": "qprr.flightstack.cli:register_flightstack_cli",
    "log": "qprr.flightlog.cli:register_flightlog_cli",
}
"""The packages' command groups: command -> ``module:function``, the function ``(subparsers)`` that adds it (the form of
an entry point; the module is imported when the group is built).  A command line
that names one of them builds that group's parser alone (:func:`build_parser`), so ``qprr analyze ...`` does not import
the viewer, the campaigns or the scenario table."""


# ------------------------------------------------------------------------------ simulate
def _cmd_simulate(args: argparse.Namespace) -> int:
    from ..scenarios import SCENARIOS
    from ..viz import plot_result

    prog = "qprr simulate"
    if args.scenario not in SCENARIOS:
        return fail(prog, f"unknown scenario {args.scenario!r}; valid: {', '.join(SCENARIOS)}")
    sc = SCENARIOS[args.scenario]
    options = {}
    for key in ("duration", "dt", "integrator", "seed", "law"):
        value = getattr(args, key)
        if value is not None:
            if key not in sc.options:
                return fail(prog, f"--{key} does not apply to scenario {sc.name!r}; its options: {', '.join(sc.options) or 'none'}")
            options[key] = value
    for item in args.set or ():
        if "=" not in item:
            return fail(prog, f"--set {item!r}: expected NAME=VALUE")
        key, value = item.split("=", 1)
        if key not in sc.options:
            return fail(prog, f"--set {key!r}: not an option of scenario {sc.name!r}; valid: {', '.join(sc.options) or 'none'}")
        try:
            options[key] = option_value(value, sc.options[key].default, key)
        except ValueError as exc:
            return fail(prog, f"--set {key}={value}: {exc}")
    if args.thesis_as_printed:
        if "as_printed" not in sc.options:
            takes = ", ".join(n for n, s in SCENARIOS.items() if "as_printed" in s.options)
            return fail(prog, f"--thesis-as-printed does not apply to scenario {sc.name!r}; scenarios that take it: {takes}")
        options["as_printed"] = True
    if args.controller is not None and args.controller not in sc.controller_names():
        return fail(prog, f"unknown controller {args.controller!r} for {sc.name!r}; valid: {', '.join(sc.controller_names())}")
    try:
        plot_path = output_path(args.plot, (".png", ".pdf", ".svg"), "plot")
        save_path = output_path(args.save, (".npz", ".csv", ".parquet"), "save")
        anim_path = output_path(args.animate, (".gif", ".mp4"), "animate")
    except ValueError as exc:
        return fail(prog, str(exc))
    if args.gains is not None:
        if "gains" not in sc.options:
            return fail(
                prog,
                f"--gains does not apply to scenario {sc.name!r} (it sets its own); scenarios that take it: "
                f"{', '.join(n for n, s in SCENARIOS.items() if 'gains' in s.options)}",
            )
        options["gains"] = args.gains
    platform = None
    if any(x is not None for x in (args.platform, args.layout, args.urdf, args.rotors, args.ee_frame)):
        name = args.platform or (DEFAULT_PLATFORM if args.urdf is None else args.urdf)
        if sc.platforms is not None and name not in sc.platforms:
            generic = ", ".join(n for n, s in SCENARIOS.items() if s.platforms is None)
            return fail(prog, f"scenario {sc.name!r} runs on {', '.join(sc.platforms)}, not on {name!r}; scenarios for any platform: {generic}")
        try:
            platform = platform_from_args(args)
        except QprrError as exc:
            return fail(prog, f"--platform {name!r}: {exc}" if args.platform and not args.urdf else str(exc))
    if args.print_gains:
        return _print_gains(sc, platform, args.controller, options)
    progress = not args.quiet
    try:
        res = sc.run(platform=platform, controller=args.controller, progress=progress, **options)
        code = 0
    except QprrError as err:
        res = err.result
        if res is None:
            return fail(prog, f"{type(err).__name__}: {err}")
        print(f"{prog}: {type(err).__name__}: {err}", file=sys.stderr)
        code = 1
    print(_summary(res))
    if sc.summary is not None and code == 0:
        for line in sc.summary(res):
            print(line)
    if save_path is not None:
        print(f"saved {_save(res, save_path)}")
    if plot_path is not None:
        plot = sc.plot if (sc.plot is not None and code == 0) else plot_result
        print(f"figure {plot(res, plot_path)}")
    if anim_path is not None:
        _animate(res, platform, anim_path, progress)
    return code


def _save(res, path: Path) -> Path:
    """The run in ``path``: ``.npz`` (SimResult.save) or a long table (``.csv``, ``.parquet``: qprr.sim.export)."""
    from ..sim.export import save_table

    return res.save(path) if path.suffix == ".npz" else save_table(res, path)


def _print_gains(sc, platform, controller: str | None, options: dict) -> int:
    """Print the gains ``controller`` (None: the scenario's, or the one its mission file names) gets in scenario ``sc``
    on ``platform`` with the run's ``options`` (``--print-gains``), without running."""
    from ..control.gains import gain_lines
    from ..platforms import load as load_platform
    from ..scenarios.missions import flown_controller, flown_gain_arguments, flown_gain_source

    platform = platform or load_platform()
    spec = options.get("gains") or (sc.options["gains"].default if "gains" in sc.options else "class")
    values = {**{k: o.default for k, o in sc.options.items()}, **options}
    try:
        controller = flown_controller(sc.name, controller, values)  # a mission file may name it
        kwargs = flown_gain_arguments(sc.name, controller, platform, spec, values)
        source = flown_gain_source(sc.name, spec, values)
    except QprrError as exc:
        return fail("qprr simulate", f"--gains {spec!r}: {exc}")
    print(f"gains of {controller} in {sc.name} on {platform.name} ({source})")
    for line in gain_lines(kwargs, platform.xi_names) if kwargs else [f"  the defaults of the {controller} class"]:
        print(line)
    return 0


def _animate(res, platform, path: Path, progress: bool) -> None:
    """Animate ``res`` to ``path``; :func:`qprr.viz.cli.animate_to_file` prints where it went (one line)."""
    from ..platforms import load as load_platform
    from ..viz import cli as viz_cli

    viz_cli.animate_to_file(platform or load_platform(), res, path, progress=progress)


def _summary(res) -> str:
    import numpy as np

    from ..control.mpc_stats import solve_summary

    e = res.rmse()
    kinds = (
        ("m",) * 3
        + ("rad",) * 3
        + tuple("m" if k == "prismatic" else "rad" if k == "revolute" else "m or rad" for k in (res.arm_kinds or ("",) * res.n_arm))
    )
    lines = [
        f"scenario {res.scenario}, platform {res.platform}, controller {res.controller}: {res.status} ({res.reason}); "
        f"{res.n} steps of {res.control_period * 1e3:g} ms in {res.wall_time:.3f} s",
        "RMSE (6.26): " + ", ".join(f"{k} {v:.3e} {u}" for (k, v), u in zip(e.items(), kinds)),
        f"rotor saturation on {100 * res.saturation_fraction():.2f} % of the steps; "
        f"max |CoG offset in B| = {1e3 * float(np.max(np.hypot(res.x_cm[:, 0], res.x_cm[:, 1]))):.2f} mm",
    ]
    mpc_line = solve_summary(res.metrics)  # the MPC's solve statistics (None for other controllers)
    if mpc_line is not None:
        lines.append(mpc_line)
    return "\n".join(lines)


def _cmd_compare(args: argparse.Namespace) -> int:
    if not COMPARISONS:
        return fail("qprr compare", "no comparison is registered (qprr.registry.COMPARISONS is empty: no plug-in provides one)")
    names = args.names or [next(iter(COMPARISONS))]
    bad = [n for n in names if n not in COMPARISONS and n != "all"]
    if bad:
        return fail("qprr compare", f"unknown comparison {bad[0]!r}; valid: {', '.join(COMPARISONS)}, all")
    if args.plot is not None and not Path(args.plot).is_dir():
        return fail("qprr compare", f"--plot {args.plot!r}: folder does not exist")
    names = list(COMPARISONS) if "all" in names else names
    batches: dict = {}  # runner -> its names, in the order asked (one runner shares its runs between them)
    for n in names:
        batches.setdefault(COMPARISONS[n], []).append(n)
    t0 = time.perf_counter()
    ok = True
    duration = None if args.duration == 30.0 else args.duration
    progress = not args.quiet
    reports = [rep for runner, batch in batches.items() for rep in runner(batch, duration=duration, plot_dir=args.plot, progress=progress)]
    for rep in reports:
        print(f"== {rep.name}")
        for line in rep.lines:
            print(line)
        for fig in rep.figures:
            print(f"figure {fig}")
        ok &= rep.ok
    print(f"total {time.perf_counter() - t0:.2f} s")
    return 0 if ok else 1


def _cmd_check(args: argparse.Namespace) -> int:
    import os

    try:
        cache = cache_dir(args.cache_dir)
    except ValueError as exc:
        return fail("qprr check", str(exc))
    if cache is not None:  # read by the suites that cache derived models (the thesis's sympy model)
        os.environ["QPRR_CACHE_DIR"] = str(cache)
    if not CHECKS:
        return fail("qprr check", "no check suite is registered (qprr.registry.CHECKS is empty: no plug-in provides one)")
    return max(run(args.verbose) for run in CHECKS.values())


def _scenario_help() -> str:
    from ..scenarios import SCENARIOS

    lines = []
    for title, group in (
        ("any platform (--platform NAME or --urdf F --rotors F.toml)", lambda s: s.platforms is None),
        ("thesis (the Q-PRR)", lambda s: s.platforms is not None),
    ):
        lines.append(f"{title}:")
        for name, sc in SCENARIOS.items():
            if not group(sc):
                continue
            where = f" [{sc.source}]" if sc.source else ""
            on = f"; platforms: {', '.join(sc.platforms)}" if sc.platforms else ""
            lines.append(f"  {name:<15} {sc.description}{where}")
            lines.append(f"  {'':<15} controllers: {', '.join(sc.controller_names())}{on}")
            opts = ", ".join(f"{k}={o.default!r}" for k, o in sc.options.items())
            lines.append(f"  {'':<15} options: {opts}")
    return "\n".join(lines)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``qprr`` command line: ``simulate``, ``compare``, ``check``, then the plug-ins' and the packages' command groups.

    ``command``: a command of :data:`GROUP_COMMANDS` to build the parser of that group alone (what :func:`main` does
    when the command line names one); None: every command (``qprr --help`` lists them all).
    """
    parser = Parser(prog="qprr", description="qprr: aerial manipulators on Pinocchio (the thesis's Q-PRR as flagship).")
    parser.add_argument("--version", action="version", version=f"qprr {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser)
    if command in GROUP_COMMANDS:
        _group_registrar(GROUP_COMMANDS[command])(sub)
        return parser
    _add_simulate(sub)
    _add_compare(sub)
    _add_check(sub)
    for register_cli in COMMANDS.values():  # plug-ins' command groups (the thesis: urdf)
        register_cli(sub)
    for target in dict.fromkeys(GROUP_COMMANDS.values()):  # optional packages load when a command runs
        _group_registrar(target)(sub)
    return parser


def _group_registrar(target: str):
    """The function ``module:function`` of :data:`GROUP_COMMANDS` names (its module imported now)."""
    module, _, function = target.partition(":")
    return vars(import_module(module))[function]


def _add_simulate(sub) -> None:
    """``qprr simulate SCENARIO``: a named scenario on any platform or the thesis's."""
    p = sub.add_parser(
        "simulate",
        help="run a named scenario (prints RMSE; optional figure, .npz, animation)",
        description="Run a named scenario.\n\nscenarios:\n" + _scenario_help(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scenario", help="a scenario name (listed above)")
    p.add_argument("--controller", default=None, help="override the scenario's controller (see the list above)")
    add_platform_options(p)
    p.add_argument("--plot", default=None, metavar="FILE.png", help="save a figure of the run (the folder must exist)")
    p.add_argument(
        "--save",
        default=None,
        metavar="FILE.npz",
        help="save the logged run: .npz (everything, for qprr), or .csv / .parquet (long format: time, series, value, unit; "
        "parquet needs the parquet extra); the folder must exist",
    )
    p.add_argument("--animate", default=None, metavar="FILE.gif", help="save a 3-D animation (.gif, or .mp4 with ffmpeg)")
    p.add_argument("--duration", type=real(positive=True, unit="s"), default=None, help="seconds (default: the scenario's)")
    p.add_argument("--dt", type=real(positive=True, unit="s"), default=None, help="integration step [s] (default 1e-3)")
    p.add_argument(
        "--integrator",
        default=None,
        choices=tuple(INTEGRATORS),
        help="; ".join(f"{name}{' (default)' if name == INTEGRATORS.default else ''}: {entry.description}" for name, entry in INTEGRATORS.items()),
    )
    p.add_argument("--seed", type=integer(lo=0), default=None, help="noise seed (default 0)")
    p.add_argument(
        "--law",
        default=None,
        choices=("septic", "quintic", "thesis"),
        help="transition law: septic (default, jerk-continuous), quintic, or thesis (the printed (6.16))",
    )
    p.add_argument("--set", action="append", metavar="NAME=VALUE", help="any scenario option (listed above), repeatable")
    p.add_argument(
        "--thesis-as-printed",
        action="store_true",
        help="the thesis's settings as printed, where they are stable (static-dsid, static-mfc: quintic law, printed gains; "
        "static-idc is refused: Table 6.2 is unstable as printed)",
    )
    p.add_argument(
        "--gains",
        default=None,
        metavar="FILE.toml|NAME",
        help="gain set of a generic scenario: platform (derived, default), class, a registered table (PLATFORM:TABLE), "
        "or a TOML file ([targets], [<controller>.gains]; docs/simulation.md)",
    )
    p.add_argument("--print-gains", action="store_true", help="print the controller's gains on the platform and exit")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_simulate)


def _add_compare(sub) -> None:
    """``qprr compare [NAME ...]``: the Chapter 6 comparisons."""
    p = sub.add_parser(
        "compare",
        help="the Chapter 6 comparisons: Table 6.3 (default), overlays, noise, sweeps, decoupled, mpc, ...",
        description="Print (and with --plot draw) the Chapter 6 comparisons: table (Table 6.3, default), overlay "
        "(Figs. 6.19-6.21), noise (Fig. 6.23), sweeps (Figs. 6.42-6.45), decoupled (coupled vs decoupled, "
        "Sec. 6.2.2), mpc (receding-horizon MPC vs IDC), realistic (motor lag, wind, friction), lag (motor time "
        "constants), or all.",
    )
    p.add_argument("names", nargs="*", metavar="NAME", help="comparisons to run (default: table)")
    p.add_argument("--plot", default=None, metavar="DIR", help="save the figures into this existing folder")
    p.add_argument("--duration", type=real(positive=True, unit="s"), default=30.0, help="mission seconds (default 30)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_compare)


def _add_check(sub) -> None:
    """``qprr check``: the model against the thesis's closed forms."""
    p = sub.add_parser(
        "check",
        help="check the model against the thesis's closed forms (table of verdicts)",
        description="Check the model against the thesis's closed forms; prints a table of verdicts, "
        "exit code 0 iff all hold.  The sympy Lagrange model (test extra) is derived once per parameter "
        "set and its generated code cached in $QPRR_CACHE_DIR, else $XDG_CACHE_HOME/qprr, else "
        "~/.cache/qprr (about 50 kB per parameter set; safe to delete).",
    )
    p.add_argument("-v", "--verbose", action="store_true", help="print the evidence behind each verdict")
    p.add_argument(
        "--cache-dir",
        default=None,
        metavar="DIR",
        help="folder of the sympy model's cache (default: $QPRR_CACHE_DIR or ~/.cache/qprr); made if its parent exists",
    )
    p.set_defaults(func=_cmd_check)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    command = argv[0] if argv else None  # the command comes first (the top level has --help and --version only)
    parser = build_parser(command)
    args = parser.parse_args(argv)
    prog = f"qprr {args.command}"
    try:
        return int(args.func(args) or 0)
    except QprrError as exc:
        return fail(prog, f"{type(exc).__name__}: {exc}")
    except MemoryError as exc:  # numpy's ArrayMemoryError names the size: say which options set it
        sized = [f"--{k}" for k in ("duration", "dt", "samples") if vars(args).get(k) is not None]
        return fail(prog, f"MemoryError: {exc}" + (f" (set by {', '.join(sized)}: ask for less)" if sized else ""))


if __name__ == "__main__":
    sys.exit(main())
