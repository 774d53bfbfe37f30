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


def _fail(prog: str, message: str) -> int:
    print(f"{prog}: error: {message}", file=sys.stderr)
    return 2


def _output_path(path: str | None, suffixes: tuple[str, ...], what: str) -> Path | None:
    """Check an output path before a run: known suffix, existing folder (nothing is created)."""
    if path is None:
        return None
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise ValueError(f"--{what} {path!r}: the file must end in {' or '.join(suffixes)}")
    if not p.parent.is_dir():
        raise ValueError(f"--{what} {path!r}: folder {str(p.parent)!r} does not exist")
    return p


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
    from .platforms import NAMES
    from .platforms import load as load_platform
    from .scenarios import SCENARIOS
    from .viz import plot_result

    prog = "qprr simulate"
    if args.scenario not in SCENARIOS:
        return _fail(prog, f"unknown scenario {args.scenario!r}; valid: {', '.join(SCENARIOS)}")
    sc = SCENARIOS[args.scenario]
    options = {}
    for key in ("duration", "dt", "integrator", "seed", "law"):
        value = getattr(args, key)
        if value is not None:
            if key not in sc.options:
                return _fail(prog, f"--{key} does not apply to scenario {sc.name!r}; its options: {', '.join(sc.options) or 'none'}")
            options[key] = value
    for item in args.set or ():
        if "=" not in item:
            return _fail(prog, f"--set {item!r}: expected NAME=VALUE")
        key, value = item.split("=", 1)
        if key not in sc.options:
            return _fail(prog, f"--set {key!r}: not an option of scenario {sc.name!r}; valid: {', '.join(sc.options) or 'none'}")
        try:
            options[key] = _convert(value, sc.options[key].default)
        except ValueError as exc:
            return _fail(prog, f"--set {key}={value}: {exc}")
    if args.controller is not None and args.controller not in sc.controllers:
        return _fail(prog, f"unknown controller {args.controller!r} for {sc.name!r}; valid: {', '.join(sc.controllers)}")
    try:
        plot_path = _output_path(args.plot, (".png", ".pdf", ".svg"), "plot")
        save_path = _output_path(args.save, (".npz",), "save")
        anim_path = _output_path(getattr(args, "animate", None), (".gif", ".mp4"), "animate")
    except ValueError as exc:
        return _fail(prog, str(exc))
    platform = None
    if args.platform is not None or args.layout is not None:
        name = args.platform or "q-prr"
        if sc.platforms is not None and name not in sc.platforms:
            return _fail(prog, f"scenario {sc.name!r} runs on {', '.join(sc.platforms)}, not on {name!r}")
        try:
            if name == "q-prr":
                platform = load_platform("q-prr", layout=args.layout or "plus")
            elif args.layout is not None:
                from .nomenclature import build

                platform = build(name, layout=args.layout)
            else:
                platform = load_platform(name) if name in NAMES else __import__("qprr").build(name)
        except QprrError as exc:
            return _fail(prog, f"--platform {name!r}: {exc}")
    progress = not args.quiet and sys.stderr.isatty()
    try:
        res = sc.run(platform=platform, controller=args.controller, progress=progress, **options)
        code = 0
    except QprrError as err:
        res = getattr(err, "result", None)
        if res is None:
            return _fail(prog, f"{type(err).__name__}: {err}")
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

    e = res.rmse()
    lines = [f"scenario {res.scenario}, platform {res.platform}, controller {res.controller}: {res.status} ({res.reason}); "
             f"{res.n} steps of {res.control_period * 1e3:g} ms in {res.wall_time:.3f} s",
             "RMSE (6.26): " + ", ".join(f"{k} {v:.3e}" for k, v in e.items()),
             f"rotor saturation on {100 * res.saturation_fraction():.2f} % of the steps; "
             f"max |CoG offset in B| = {1e3 * float(np.max(np.hypot(res.x_cm[:, 0], res.x_cm[:, 1]))):.2f} mm"]
    return "\n".join(lines)


def _cmd_compare(args: argparse.Namespace) -> int:
    from .thesis.scenarios import compare

    if not (args.duration > 0):
        return _fail("qprr compare", f"--duration must be > 0 s, got {args.duration!r}")
    t0 = time.perf_counter()
    cmp = compare(duration=args.duration, progress=not args.quiet and sys.stderr.isatty())
    print("RMSE (6.26) on the static-manipulator mission (Sec. 6.3.1.4), ours vs Thesis Table 6.3;")
    print("thesis columns: IDC, MPC (= our dsid), MFC; times: our wall time vs the thesis's T_x")
    print(cmp.table())
    print(f"total {time.perf_counter() - t0:.2f} s")
    return 0 if all(s == "ok" for s in cmp.status.values()) else 1


def _cmd_check(args: argparse.Namespace) -> int:
    from .thesis.checks import main as check_main

    return check_main(verbose=args.verbose)


def _cmd_urdf(args: argparse.Namespace) -> int:
    from .thesis.urdf import URDF_PATH, write_urdf

    try:
        out = _output_path(args.output, (".urdf",), "output") if args.output else URDF_PATH
    except ValueError as exc:
        return _fail("qprr urdf", str(exc))
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
    p.add_argument("--platform", default=None, help="q-prr (default), borinot_flying_arm_2, hextilt_flying_arm_5 or a (2.1) name "
                   "such as HEX-RRR (generic scenarios only)")
    p.add_argument("--layout", default=None, choices=("plus", "x"), help="rotor layout of the Q-PRR or of a built platform")
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
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_simulate)

    p = sub.add_parser("compare", help="IDC vs desired-state ID (thesis: MPC) vs MFC: RMSE table shaped like Table 6.3")
    p.add_argument("--duration", type=float, default=30.0, help="seconds (default 30)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser("check", help="check the model against the thesis's closed forms (table of verdicts)")
    p.add_argument("-v", "--verbose", action="store_true", help="print the evidence behind each verdict")
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
        if dt is not None and not dt > 0:
            return _fail(f"qprr {args.command}", f"--dt must be > 0 s, got {dt!r}")
        duration = getattr(args, "duration", None)
        if args.command == "simulate" and duration is not None and not duration > 0:
            return _fail("qprr simulate", f"--duration must be > 0 s, got {duration!r}")
        return int(args.func(args) or 0)
    except QprrError as exc:
        return _fail(f"qprr {args.command}", f"{type(exc).__name__}: {exc}")


if __name__ == "__main__":
    sys.exit(main())
