"""``qprr design run SPEC`` / ``qprr design report RESULTS`` / ``qprr design show SPEC``.

Registered in :func:`qprr.cli.build_parser` through :func:`register_design_cli` (as :mod:`qprr.campaign.cli`).
Exit codes: 0 done, 1 interrupted, 2 bad arguments or specification, 3 no design of the study is feasible (the
summary says which constraint excluded how many designs, and why each design is out).
"""

from __future__ import annotations

import argparse
import sys

from ..cli.common import add_store_options, integer
from ..errors import QprrError


def _fail(prog: str, message: str) -> int:
    print(f"{prog}: error: {message}", file=sys.stderr)
    return 2


def _print_report(results, out, args) -> None:
    from .report import design_report

    text, figures = design_report(results, out, top=args.top, fly=not args.no_flight, backend=args.flight_backend)
    print(text)
    for f in figures:
        print(f"figure {f}")


def _cmd_run(args: argparse.Namespace) -> int:
    from .search import infeasible_reasons, run_design
    from .spec import DesignSpec

    prog = "qprr design run"
    try:
        spec = DesignSpec.load(args.spec)
        done = run_design(
            spec,
            args.output or f"{spec.name}.csv",
            backend=args.backend,
            workers=args.workers,
            scheduler=args.scheduler,
            fresh=args.fresh,
            progress=not args.quiet,
        )
        n = len(done.results)
        print(
            f"{spec.name}: {done.executed} designs evaluated now ({done.skipped} resumed), {n} saved in {done.path}; "
            f"{done.failed} failed; {done.wall_time:.1f} s on {done.backend}"
        )
        if not args.report or done.interrupted:  # the report's text gives them otherwise
            for line in infeasible_reasons(done.results, spec):
                print(line)
        n_feasible = int(sum(done.results.table["feasible"]))
        if args.report and not done.interrupted:
            _print_report(done.results, args.report, args)
    except (QprrError, KeyError, ValueError) as exc:
        return _fail(prog, f"{type(exc).__name__}: {exc}")
    if done.interrupted:
        return 1
    if n_feasible == 0:
        print(f"{prog}: no feasible design among the {n} of {spec.name} (the reasons above)", file=sys.stderr)
        return 3
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    try:
        _print_report(args.results, args.out, args)
    except (QprrError, KeyError, ValueError) as exc:
        return _fail("qprr design report", f"{type(exc).__name__}: {exc}")
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    from .search import grid_points, n_points, reference_points
    from .spec import DesignSpec

    try:
        spec = DesignSpec.load(args.spec)
    except (QprrError, KeyError, ValueError) as exc:
        return _fail("qprr design show", f"{type(exc).__name__}: {exc}")
    s = spec.search
    how = "grid" if s.method == "grid" else f"NSGA-II ({s.optimiser}) over {', '.join(spec.optimised)}: {s.generations} generations x {s.population}"
    what = f"{len(spec.architectures)} architectures ({', '.join(spec.architectures)})" if spec.robot is None else f"robot {spec.robot.name}"
    print(
        f"{spec.name}: {what}, {len(spec.references)} references; "
        f"{how}; {n_points(spec)} designs; {spec.effort.samples} samples per map; seed {spec.seed}; fingerprint {spec.fingerprint}"
    )
    print(
        f"  objectives: {', '.join(spec.objectives)}; constraints: "
        + (", ".join(_bound(k, lo, hi) for k, (lo, hi) in spec.constraints.items()) or "none")
    )
    pts = reference_points(spec) + (grid_points(spec) if s.method == "grid" else [])
    for p in pts[: args.first]:
        print(f"  design {p['run']}: {p['name']} " + ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in p["params"].items()))
    return 0


def _bound(k: str, lo, hi) -> str:
    return " and ".join(b for b in ((f"{k} >= {lo:g}" if lo is not None else ""), (f"{k} <= {hi:g}" if hi is not None else "")) if b)


def _report_args(r) -> None:
    r.add_argument("--top", type=integer(lo=0), default=None, help="designs flown in the closed-loop check (default: the study's closed_loop.top)")
    r.add_argument("--no-flight", action="store_true", help="skip the closed-loop check")
    r.add_argument(
        "--flight-backend",
        default="inline",
        choices=("local", "dask", "inline"),
        help="where the closed-loop flights run (default inline: a few flights)",
    )


def register_design_cli(sub) -> None:
    """Add ``design run | report | show`` to the ``qprr`` command line."""
    p = sub.add_parser(
        "design",
        help="design search over the (2.1) nomenclature or your own robot (a URDF with placeholders): Pareto fronts",
        description="Design studies (qprr.design): evaluate candidate aerial manipulators on the design maps, "
        "find the Pareto front, rank and fly the best.",
    )
    dsub = p.add_subparsers(dest="design_command", required=True, parser_class=type(p))

    r = dsub.add_parser("run", help="run a design study (.toml/.json); resumes an interrupted one")
    r.add_argument("spec", help="design study, e.g. examples/design/thesis_architectures.toml")
    add_store_options(r)
    r.add_argument("--report", default=None, metavar="DIR", help="then write the report (summary.md, ranking, figures) into DIR")
    r.add_argument("--quiet", action="store_true", help="no progress lines")
    _report_args(r)
    r.set_defaults(func=_cmd_run)

    r = dsub.add_parser("report", help="ranked table, Pareto figures and closed-loop check of a study's results")
    r.add_argument("results", help="results file (.csv or .parquet) with its .meta.json beside it")
    r.add_argument("--out", default=None, metavar="DIR", help="write summary.md, ranking.csv, closed_loop.csv and the figures into DIR")
    _report_args(r)
    r.set_defaults(func=_cmd_report)

    r = dsub.add_parser("show", help="print a study's size, fingerprint and first designs")
    r.add_argument("spec", help="design study (.toml or .json)")
    r.add_argument("--first", type=integer(lo=1), default=8, help="designs to list (default 8)")
    r.set_defaults(func=_cmd_show)
