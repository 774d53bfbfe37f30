"""``qprr campaign run SPEC`` / ``qprr campaign report RESULTS`` / ``qprr campaign show SPEC``.

Registered in :func:`qprr.cli.build_parser` through :func:`register_campaign_cli`.  Exit codes of ``run``:
0 done (every run asked for saved, whatever their status), 1 runs remain (interrupted by Ctrl-C
or SIGTERM, or lost with a worker or the scheduler: run the same command again), 2 bad
arguments, specification or results file (a bad row is named with its file, line and column),
3 the results could not be written (full disk, read-only folder: one line naming the file and
the error; the rows saved before are kept).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

from ..cli.common import add_store_options, integer
from ..cli.common import fail as _fail
from ..errors import QprrError


def _print(lines) -> None:
    """Print ``lines`` on stdout; a reader that has gone (``qprr campaign show SPEC | head -1``) ends the output quietly:
    stdout then points to the null device, so that neither this nor the interpreter's last flush raises BrokenPipeError."""
    try:
        for line in lines:
            print(line)
        sys.stdout.flush()
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


def _cmd_run(args: argparse.Namespace) -> int:
    from .metrics import RunStatus
    from .report import campaign_report, not_ok_reasons
    from .runner import run_campaign
    from .spec import CampaignSpec
    from .store import ResultsWriteError

    prog = "qprr campaign run"
    try:
        spec = CampaignSpec.load(args.spec)
        output = args.output or f"{spec.name}.csv"
        t0 = time.perf_counter()
        done = run_campaign(
            spec,
            output,
            backend=args.backend,
            workers=args.workers,
            scheduler=args.scheduler,
            fresh=args.fresh,
            limit=args.limit,
            progress=not args.quiet,
        )
    except ResultsWriteError as exc:
        print(
            f"{prog}: error: {exc}; the campaign stopped (no run started after it), the rows saved before are kept: "
            f"run the same command again once the file can be written",
            file=sys.stderr,
        )
        return 3
    except (QprrError, KeyError, ValueError) as exc:
        return _fail(prog, f"{type(exc).__name__}: {exc}")
    wall = time.perf_counter() - t0
    res = done.results
    ok = int((res.table["status"] == RunStatus.OK).sum()) if len(res) else 0
    lost = f", {done.lost} lost (not saved)" if done.lost else ""
    lost += f", stopped by {done.interrupted}" if done.interrupted else ""
    _print(
        [
            f"{spec.name}: {done.executed} runs now ({done.skipped} resumed{lost}), {len(res)}/{spec.n_runs} saved in {done.path}; "
            f"{ok} ok, {len(res) - ok} not ok; {wall:.1f} s, {done.runs_per_second:.2f} runs/s on {done.where}"
        ]
    )
    for line in not_ok_reasons(res):
        print(line)
    if done.interrupted or done.lost:
        return 1
    if args.report:
        text, figures = campaign_report(res, args.report)
        _print([text, *(f"figure {f}" for f in figures)])
    return 0


def _cmd_report(args: argparse.Namespace) -> int:
    from .report import campaign_report

    try:
        text, figures = campaign_report(
            args.results,
            args.out,
            by=args.by,
            metrics=args.metric,
            heatmap=args.heatmap,
            curve=args.curve,
            scatter=args.scatter,
            markdown=args.markdown,
        )
    except (QprrError, KeyError, ValueError) as exc:
        return _fail("qprr campaign report", f"{type(exc).__name__}: {exc}")
    _print([text, *(f"figure {f}" for f in figures)])
    return 0


def _cmd_show(args: argparse.Namespace) -> int:
    from .metrics import metric_columns
    from .spec import CampaignSpec
    from .worker import platform_of

    try:
        spec = CampaignSpec.load(args.spec)
        platform = platform_of(spec)
    except (QprrError, KeyError, ValueError) as exc:
        return _fail("qprr campaign show", f"{type(exc).__name__}: {exc}")
    target = f"scenario {spec.scenario}" if spec.scenario else f"callable {spec.callable}"
    given = "" if spec.platform_label == platform.name else f" ({spec.platform_label})"
    head = (
        f"{spec.name}: {target} on {platform.name}{given}; {spec.n_points} grid points x {spec.samples} samples = "
        f"{spec.n_runs} runs; seed {spec.seed}; fingerprint {spec.fingerprint}"
    )
    runs = (spec.run(i) for i in range(min(args.first, spec.n_runs)))
    _print(
        [
            head,
            f"  metrics: {', '.join(metric_columns(spec.metrics, platform.xi_names, spec.extras))}",
            *(f"  run {run.index}: seed {run.seed}, " + ", ".join(f"{k}={v!r}" for k, v in run.params.items()) for run in runs),
        ]
    )
    return 0


def register_campaign_cli(sub) -> None:
    """Add ``campaign run | report | show`` to the ``qprr`` command line."""
    p = sub.add_parser(
        "campaign",
        help="Monte-Carlo campaigns: many seeded runs, locally or on Dask, with robustness tables",
        description="Monte-Carlo campaigns (qprr.campaign): run a specification, report its results.",
    )
    csub = p.add_subparsers(dest="campaign_command", required=True, parser_class=type(p))

    r = csub.add_parser("run", help="run a campaign specification (.toml/.json); resumes an interrupted one")
    r.add_argument("spec", help="campaign specification (.toml or .json), e.g. examples/campaigns/quickstart.toml")
    add_store_options(r)
    r.add_argument("--limit", type=integer(lo=0), default=None, help="run at most this many of the missing runs")
    r.add_argument("--report", default=None, metavar="DIR", help="then write the report (summary.md + figures) into DIR")
    r.add_argument("--quiet", action="store_true", help="no progress line")
    r.set_defaults(func=_cmd_run)

    r = csub.add_parser("report", help="summary table and figures of a campaign's results")
    r.add_argument("results", help="results file (.csv or .parquet) with its .meta.json beside it")
    r.add_argument("--out", default=None, metavar="DIR", help="write summary.md and the figures (PNG) into DIR")
    r.add_argument("--by", nargs="+", default=None, help="group columns (default: controller and the grid parameters)")
    r.add_argument(
        "--metric", nargs="+", default=None, help="metric columns (default: rmse_position, x_cm_max, saturation, recovery_time when present)"
    )
    r.add_argument("--heatmap", nargs=2, default=None, metavar=("X", "Y"), help="two swept parameters for the heat maps")
    r.add_argument("--curve", default=None, metavar="X", help="parameter of the success-rate curve (default: every numeric one)")
    r.add_argument(
        "--scatter",
        nargs=2,
        action="append",
        default=None,
        metavar=("X", "METRIC"),
        help="a scatter plot of METRIC against parameter X, coloured by the first group column (repeatable)",
    )
    r.add_argument("--markdown", action="store_true", help="print the table as Markdown")
    r.set_defaults(func=_cmd_report)

    r = csub.add_parser("show", help="print a specification's size, fingerprint and first runs")
    r.add_argument("spec", help="campaign specification (.toml or .json)")
    r.add_argument("--first", type=integer(lo=0), default=5, help="runs to list (default 5)")
    r.set_defaults(func=_cmd_show)
