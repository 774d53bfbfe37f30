"""Command line: ``qprr simulate | compare | check | urdf`` (and the commands other modules register).

Errors in the arguments end in one line on stderr and exit code 2; a run that diverges prints
its error and exit code 1; otherwise 0.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from . import __version__
from .errors import QprrError


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit code 2) and no raw markup in the help."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message}\n")


def fail(prog: str, message: str) -> int:
    print(f"{prog}: error: {message}", file=sys.stderr)
    return 2


def _writable(folder: Path) -> str:
    """"" if a file can be created in ``folder`` (tried with a temporary file, removed at once), else why not."""
    import tempfile

    try:
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".qprr-write-test-"):
            pass
    except OSError as exc:
        return exc.strerror or str(exc)
    return ""


def output_path(path: str | None, suffixes: tuple[str, ...], what: str) -> Path | None:
    """Check an output path before a run: known suffix, existing and writable folder (nothing is created).

    Shared by every command group (``simulate``, ``analyze``, ``wheeled``, ``animate``...); raises
    ValueError with a one-line message naming the option ``--what`` and the path."""
    if path is None:
        return None
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise ValueError(f"--{what} {path!r}: the file must end in {' or '.join(suffixes)}")
    if not p.parent.is_dir():
        raise ValueError(f"--{what} {path!r}: folder {str(p.parent)!r} does not exist")
    if p.is_dir():
        raise ValueError(f"--{what} {path!r} is a folder, not a file")
    why = _writable(p.parent)
    if why:
        raise ValueError(f"--{what} {path!r}: cannot write in folder {str(p.parent)!r} ({why})")
    return p


def _cache_dir(path: str | None) -> Path | None:
    """Check ``--cache-dir``: an existing writable folder, or a new one whose parent folder exists (then made)."""
    if path is None:
        return None
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ValueError(f"--cache-dir {path!r} is a file, not a folder")
    if not p.exists():
        if not p.parent.is_dir():
            raise ValueError(f"--cache-dir {path!r}: folder {str(p.parent)!r} does not exist")
        try:
            p.mkdir()
        except OSError as exc:
            raise ValueError(f"--cache-dir {path!r}: cannot create it ({exc.strerror or exc})") from None
    why = _writable(p)
    if why:
        raise ValueError(f"--cache-dir {path!r}: cannot write in it ({why})")
    return p


PLATFORM_HELP = ("q-prr (default), borinot_flying_arm_2, hextilt_flying_arm_5 or a (2.1) name such as HEX-RRR; "
                 "your own: --urdf FILE.urdf --rotors FILE.toml")


def add_platform_options(p: argparse.ArgumentParser, *, name_option: bool = True) -> None:
    """``--platform NAME`` (unless the command takes the name as a positional argument), ``--layout plus|x``
    and a user's own platform: ``--urdf FILE --rotors FILE.toml [--ee-frame NAME]``; read back by
    :func:`platform_from_args`."""
    if name_option:
        p.add_argument("--platform", default=None, help=PLATFORM_HELP)
    p.add_argument("--layout", default=None, choices=("plus", "x"), help="rotor layout of the Q-PRR or of a built platform")
    p.add_argument("--urdf", default=None, metavar="FILE.urdf", help="your own platform: its URDF (docs/platforms.md); with --rotors")
    p.add_argument("--rotors", default=None, metavar="FILE.toml", help="the rotor description of --urdf")
    p.add_argument("--ee-frame", default=None, metavar="NAME", help="end-effector frame of --urdf (default: the last frame of the arm)")


def platform_from_args(args: argparse.Namespace):
    """The platform named by the options of :func:`add_platform_options` (:func:`qprr.platforms.resolve`);
    raises :class:`~qprr.errors.QprrError` with the option names in its message."""
    from .errors import InputError
    from .platforms import resolve

    layout = args.layout

    if args.urdf is None and (args.rotors is not None or args.ee_frame is not None):
        raise InputError("--rotors and --ee-frame describe your own platform: give its --urdf too")
    if args.urdf is not None and args.rotors is None:
        raise InputError(f"--urdf {args.urdf!r} needs --rotors FILE.toml (the URDF format has no rotors; docs/platforms.md)")
    if args.urdf is not None and (args.platform is not None or layout is not None):
        raise InputError("--urdf names your own platform: leave out --platform and --layout")
    return resolve(args.platform, layout=layout, urdf=args.urdf, rotors=args.rotors, ee_frame=args.ee_frame)


def _convert(value: str, default):
    """A ``--set`` value converted to the type of the option's default."""
    if isinstance(default, bool):
        if value.lower() in ("1", "true", "yes", "on"):
            return True
        if value.lower() in ("0", "false", "no", "off"):
            return False
        raise ValueError(f"expected true or false, got {value!r}")
    if isinstance(default, int):
        return int(value)
    if isinstance(default, float):
        return float(value)
    if isinstance(default, tuple):
        return tuple(float(x) for x in value.split(","))
    return value


# ------------------------------------------------------------------------------ simulate
def _cmd_simulate(args: argparse.Namespace) -> int:
    from .scenarios import SCENARIOS
    from .viz import plot_result

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
            options[key] = _convert(value, sc.options[key].default)
        except ValueError as exc:
            return fail(prog, f"--set {key}={value}: {exc}")
    if args.controller is not None and args.controller not in sc.controllers:
        return fail(prog, f"unknown controller {args.controller!r} for {sc.name!r}; valid: {', '.join(sc.controllers)}")
    try:
        plot_path = output_path(args.plot, (".png", ".pdf", ".svg"), "plot")
        save_path = output_path(args.save, (".npz",), "save")
        anim_path = output_path(getattr(args, "animate", None), (".gif", ".mp4"), "animate")
    except ValueError as exc:
        return fail(prog, str(exc))
    platform = None
    if any(x is not None for x in (args.platform, args.layout, args.urdf, args.rotors, args.ee_frame)):
        name = args.platform or ("q-prr" if args.urdf is None else args.urdf)
        if sc.platforms is not None and name not in sc.platforms:
            return fail(prog, f"scenario {sc.name!r} runs on {', '.join(sc.platforms)}, not on {name!r}")
        try:
            platform = platform_from_args(args)
        except QprrError as exc:
            return fail(prog, f"--platform {name!r}: {exc}" if args.platform and not args.urdf else str(exc))
    progress = not args.quiet and sys.stderr.isatty()
    try:
        res = sc.run(platform=platform, controller=args.controller, progress=progress, **options)
        code = 0
    except QprrError as err:
        res = getattr(err, "result", None)
        if res is None:
            return fail(prog, f"{type(err).__name__}: {err}")
        print(f"{prog}: {type(err).__name__}: {err}", file=sys.stderr)
        code = 1
    print(_summary(res))
    if sc.summary is not None and code == 0:
        for line in sc.summary(res):
            print(line)
    if save_path is not None:
        print(f"saved {res.save(save_path)}")
    if plot_path is not None:
        plot = sc.plot if (sc.plot is not None and code == 0) else plot_result
        print(f"figure {plot(res, plot_path)}")
    if anim_path is not None:
        _animate(res, platform, anim_path)
    return code


def _animate(res, platform, path: Path) -> None:
    from .platforms import load as load_platform
    from .viz.cli import animate_to_file

    print(f"animation {animate_to_file(platform or load_platform(), res, path)}")


def _summary(res) -> str:
    import numpy as np

    from .control.mpc_stats import solve_summary

    e = res.rmse()
    kinds = ("m",) * 3 + ("rad",) * 3 + tuple("m" if k == "prismatic" else "rad" if k == "revolute" else "m or rad"
                                               for k in (res.arm_kinds or ("",) * res.n_arm))
    lines = [f"scenario {res.scenario}, platform {res.platform}, controller {res.controller}: {res.status} ({res.reason}); "
             f"{res.n} steps of {res.control_period * 1e3:g} ms in {res.wall_time:.3f} s",
             "RMSE (6.26): " + ", ".join(f"{k} {v:.3e} {u}" for (k, v), u in zip(e.items(), kinds)),
             f"rotor saturation on {100 * res.saturation_fraction():.2f} % of the steps; "
             f"max |CoG offset in B| = {1e3 * float(np.max(np.hypot(res.x_cm[:, 0], res.x_cm[:, 1]))):.2f} mm"]
    mpc_line = solve_summary(res.metrics)  # the MPC's solve statistics (None for other controllers)
    if mpc_line is not None:
        lines.append(mpc_line)
    return "\n".join(lines)


def _cmd_compare(args: argparse.Namespace) -> int:
    from .thesis.comparisons import COMPARISONS, run_comparisons

    if not 0 < args.duration < float("inf"):
        return fail("qprr compare", f"--duration must be a finite number > 0 s, got {args.duration!r}")
    names = args.names or ["table"]
    bad = [n for n in names if n not in COMPARISONS and n != "all"]
    if bad:
        return fail("qprr compare", f"unknown comparison {bad[0]!r}; valid: {', '.join(COMPARISONS)}, all")
    if args.plot is not None and not Path(args.plot).is_dir():
        return fail("qprr compare", f"--plot {args.plot!r}: folder does not exist")
    t0 = time.perf_counter()
    ok = True
    duration = None if args.duration == 30.0 else args.duration
    for rep in run_comparisons(names, duration=duration, plot_dir=args.plot, progress=not args.quiet and sys.stderr.isatty()):
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
        cache = _cache_dir(args.cache_dir)
    except ValueError as exc:
        return fail("qprr check", str(exc))
    if cache is not None:  # read by qprr.thesis.symbolic when it derives (or reloads) the sympy model
        os.environ["QPRR_CACHE_DIR"] = str(cache)
    from .thesis.checks import main as check_main

    return check_main(verbose=args.verbose)


def _cmd_urdf(args: argparse.Namespace) -> int:
    from .thesis.urdf import URDF_PATH, write_urdf

    try:
        out = output_path(args.output, (".urdf",), "output") if args.output else URDF_PATH
    except ValueError as exc:
        return fail("qprr urdf", str(exc))
    print(write_urdf(out))
    return 0


def _scenario_help() -> str:
    from .scenarios import SCENARIOS

    lines = []
    for name, sc in SCENARIOS.items():
        where = f" [{sc.source}]" if sc.source else ""
        on = f"; platforms: {', '.join(sc.platforms)}" if sc.platforms else "; any platform"
        lines.append(f"  {name:<15} {sc.description}{where}")
        lines.append(f"  {'':<15} controllers: {', '.join(sc.controllers)}{on}")
        opts = ", ".join(f"{k}={o.default!r}" for k, o in sc.options.items())
        lines.append(f"  {'':<15} options: {opts}")
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="qprr", description="qprr: aerial manipulators on Pinocchio (the thesis's Q-PRR as flagship).")
    parser.add_argument("--version", action="version", version=f"qprr {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("simulate", help="run a named scenario (prints RMSE; optional figure, .npz, animation)",
                       description="Run a named scenario.\n\nscenarios:\n" + _scenario_help(),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenario", help="a scenario name (listed above)")
    p.add_argument("--controller", default=None, help="override the scenario's controller (see the list above)")
    add_platform_options(p)
    p.add_argument("--plot", default=None, metavar="FILE.png", help="save a figure of the run (the folder must exist)")
    p.add_argument("--save", default=None, metavar="FILE.npz", help="save the logged run (the folder must exist)")
    p.add_argument("--animate", default=None, metavar="FILE.gif", help="save a 3-D animation (.gif, or .mp4 with ffmpeg)")
    p.add_argument("--duration", type=float, default=None, help="seconds (default: the scenario's)")
    p.add_argument("--dt", type=float, default=None, help="integration step [s] (default 1e-3)")
    p.add_argument("--integrator", default=None, choices=("midpoint", "rk4", "euler"),
                   help="midpoint (default, 2nd order), rk4 (4th) or euler (semi-implicit, 1st)")
    p.add_argument("--seed", type=int, default=None, help="noise seed (default 0)")
    p.add_argument("--law", default=None, choices=("septic", "quintic", "thesis"),
                   help="transition law: septic (default, jerk-continuous), quintic, or thesis (the printed (6.16))")
    p.add_argument("--set", action="append", metavar="NAME=VALUE", help="any scenario option (listed above), repeatable")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_simulate)

    p = sub.add_parser("compare", help="the Chapter 6 comparisons: Table 6.3 (default), overlays, noise, sweeps, decoupled, mpc, ...",
                       description="Print (and with --plot draw) the Chapter 6 comparisons: table (Table 6.3, default), overlay "
                       "(Figs. 6.19-6.21), noise (Fig. 6.23), sweeps (Figs. 6.42-6.45), decoupled (coupled vs decoupled, "
                       "Sec. 6.2.2), mpc (receding-horizon MPC vs IDC), realistic (motor lag, wind, friction), lag (motor time "
                       "constants), or all.")
    p.add_argument("names", nargs="*", metavar="NAME", help="comparisons to run (default: table)")
    p.add_argument("--plot", default=None, metavar="DIR", help="save the figures into this existing folder")
    p.add_argument("--duration", type=float, default=30.0, help="mission seconds (default 30)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser("check", help="check the model against the thesis's closed forms (table of verdicts)",
                       description="Check the model against the thesis's closed forms; prints a table of verdicts, "
                       "exit code 0 iff all hold.  The sympy Lagrange model (test extra) is derived once per parameter "
                       "set and its generated code cached in $QPRR_CACHE_DIR, else $XDG_CACHE_HOME/qprr, else "
                       "~/.cache/qprr (about 50 kB per parameter set; safe to delete).")
    p.add_argument("-v", "--verbose", action="store_true", help="print the evidence behind each verdict")
    p.add_argument("--cache-dir", default=None, metavar="DIR",
                   help="folder of the sympy model's cache (default: $QPRR_CACHE_DIR or ~/.cache/qprr); made if its parent exists")
    p.set_defaults(func=_cmd_check)

    p = sub.add_parser("urdf", help="regenerate urdf/qprr.urdf from the thesis parameters")
    p.add_argument("-o", "--output", default=None, help="output path (default: the packaged urdf/qprr.urdf)")
    p.set_defaults(func=_cmd_urdf)

    for module in ("qprr.viz.cli", "qprr.wheeled.cli", "qprr.analysis.cli", "qprr.campaign.cli"):  # command groups of other packages
        try:
            mod = __import__(module, fromlist=["register_cli"])
        except ImportError:
            continue
        mod.register_cli(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        dt = getattr(args, "dt", None)
        if dt is not None and not 0 < dt < float("inf"):
            return fail(f"qprr {args.command}", f"--dt must be a finite number > 0 s, got {dt!r}")
        duration = getattr(args, "duration", None)
        if args.command == "simulate" and duration is not None and not 0 < duration < float("inf"):
            return fail("qprr simulate", f"--duration must be a finite number > 0 s, got {duration!r}")
        return int(args.func(args) or 0)
    except QprrError as exc:
        return fail(f"qprr {args.command}", f"{type(exc).__name__}: {exc}")


if __name__ == "__main__":
    sys.exit(main())
