"""Campaign throughput: runs per second with 1, 2, ... workers, locally and on a Dask LocalCluster.

    python benchmarks/campaign_benchmark.py [--runs 16] [--duration 30] [--workers 1 2] [--no-dask] [--quick]

* Throughput: a campaign of ``--runs`` runs of the ``static-idc`` scenario (``--duration`` s
  at 1 kHz, a random +-10 % mass error per run so that no two runs are alike) on each backend and
  worker count.  Each backend is started and warmed up first (worker processes spawned, qprr
  imported, one short run per worker), then the campaign is timed: the rate is steady-state
  throughput, startup excluded (startup is printed apart).
* Parallel efficiency: rate with n workers / (n x the rate with 1 worker of the same backend),
  all measured in this one run, side by side; ``--repeat`` interleaved rounds, the best of each
  configuration kept (the machine is shared: a round disturbed by another job is discarded).
  ``raw``: n plain Python processes running the same simulations without any campaign code,
  started together - the ceiling the machine itself sets (its two vCPUs do not give two
  independent cores' worth of simulation throughput: see docs/campaigns.md).
* Per-run overhead of the Dask path against the local one: campaigns of tiny runs (one control
  tick) of two sizes on one worker; (time(N2) - time(N1)) / (N2 - N1) is the cost of one
  task's round trip (submit, pickle, run, return, save a row), startup cancelled out.

* Against the machine: each backend's rate / the raw processes' rate with the same workers (1: no
  cost of the campaign code).

Without Dask (``pip install "qprr[dask]"``) the Dask rows are left out, with a message.  ``--quick``:
2 runs of 0.2 s, 1 worker, one round, tiny campaigns of 2 and 6 runs, local backend only: a smoke run.
The machine is shared: the load average is printed before and after; measure when it is low.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/machine.py, wherever this runs from
sys.path.insert(1, str(Path(__file__).resolve().parent.parent))  # this checkout's qprr (the workers inherit sys.path)

from machine import machine_lines

from qprr.campaign import CampaignSpec, make_backend, run_campaign


def spec(name: str, runs: int, duration: float) -> CampaignSpec:
    return CampaignSpec.from_mapping(
        {
            "name": name,
            "scenario": "static-idc",
            "seed": 1,
            "samples": runs,
            "options": {"duration": duration},
            "random": {"model.mass": {"dist": "uniform", "low": 0.9, "high": 1.1}},
        }
    )


def timed(backend, sp: CampaignSpec, folder: Path) -> float:
    t0 = time.perf_counter()
    done = run_campaign(sp, folder / f"{sp.name}-{time.perf_counter_ns()}.csv", backend=backend, progress=False)
    wall = time.perf_counter() - t0
    bad = len(done.results) - int((done.results.table["status"] == "ok").sum())
    if done.executed != sp.n_runs or bad:
        raise SystemExit(f"benchmark campaign {sp.name}: {done.executed} runs, {bad} not ok")
    return wall


_RAW = """
import sys, time
sys.path[:0] = {path!r}
from qprr.scenarios import run
from qprr.sim.mismatch import ModelError, perturbed
from qprr.thesis import load_qprr
p = load_qprr()
run("static-idc", platform=p, duration=0.01)
print(time.time())  # ready: imported and warmed up
start = {start!r}
while time.time() < start:
    time.sleep(0.001)
for k in range({n}):
    run("static-idc", platform=p, duration={duration!r}, plant=perturbed(p, ModelError(mass=0.95 + 0.01 * k)))
print(time.time())
"""


def raw(workers: int, runs: int, duration: float) -> float:
    """Rate of ``workers`` plain processes running ``runs / workers`` runs each, started together: no campaign code.

    What the machine itself allows: the ceiling of any parallel efficiency measured here."""
    import subprocess

    share = [runs // workers + (1 if k < runs % workers else 0) for k in range(workers)]
    slack = 4.0
    while True:
        start = time.time() + slack  # every process imported and warmed up by then (checked: else again, with more time)
        procs = [
            subprocess.Popen(
                [sys.executable, "-c", _RAW.format(path=sys.path[:2], start=start, n=n, duration=duration)], stdout=subprocess.PIPE, text=True
            )
            for n in share
        ]
        stamps = [[float(x) for x in p.communicate()[0].split()] for p in procs]
        late = max(ready for ready, _ in stamps) - start
        if late <= 0 or slack >= 64.0:
            if late > 0:
                print(
                    f"raw: a process was ready {late:.1f} s after the common start even with {slack:g} s of slack: "
                    f"its rate is underestimated (the machine is overloaded)",
                    flush=True,
                )
            return runs / (max(end for _, end in stamps) - start)
        slack *= 2


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=16, help="runs per timed campaign (default 16)")
    ap.add_argument("--duration", type=float, default=30.0, help="simulated seconds per run (default 30)")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="worker counts (default 1 2)")
    ap.add_argument("--repeat", type=int, default=2, help="rounds over every configuration, interleaved; the best is kept (default 2)")
    ap.add_argument("--no-dask", action="store_true", help="local backend only")
    ap.add_argument(
        "--tiny",
        type=int,
        nargs=2,
        default=[20, 220],
        metavar=("N1", "N2"),
        help="sizes of the tiny-run campaigns for the per-run overhead (default 20 220)",
    )
    ap.add_argument("--quick", action="store_true", help="2 runs of 0.2 s, 1 worker, 1 round, local only (a smoke run)")
    args = ap.parse_args(argv)
    if args.quick:
        args.runs, args.duration, args.workers, args.repeat, args.tiny, args.no_dask = 2, 0.2, [1], 1, [2, 6], True
    if not args.no_dask:
        try:
            import distributed  # noqa: F401
        except ImportError:
            print('campaign_benchmark: Dask is not installed (pip install "qprr[dask]"); the local backend only')
            args.no_dask = True
    for line in machine_lines(("dask", "distributed")):
        print(line)
    import qprr

    print(f"qprr imported from {Path(qprr.__file__).parent}")
    backends = ["local"] + ([] if args.no_dask else ["dask"])
    print(
        f"\nthroughput: {args.runs} runs of static-idc, {args.duration:g} s at 1 kHz each (steady state, warmed-up workers); "
        f"{args.repeat} interleaved rounds\n"
    )
    print(f"{'round':>5} {'backend':<8} {'workers':>7} {'startup s':>10} {'wall s':>8} {'runs/s':>8} {'load':>5}")
    print("-" * 58)
    rates: dict[tuple[str, int], list[float]] = {}
    overhead: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for rnd in range(args.repeat):
            for w in args.workers:
                rate = raw(w, args.runs, args.duration)
                rates.setdefault(("raw", w), []).append(rate)
                print(f"{rnd + 1:>5} {'raw':<8} {w:>7} {'-':>10} {args.runs / rate:>8.2f} {rate:>8.3f} {os.getloadavg()[0]:>5.2f}", flush=True)
            for be_name in backends:
                for w in args.workers:
                    t0 = time.perf_counter()
                    be = make_backend(be_name, workers=w)
                    timed(be, spec("warm-up", 2 * w, 0.01), folder)
                    startup = time.perf_counter() - t0
                    wall = timed(be, spec("throughput", args.runs, args.duration), folder)
                    if w == 1:
                        n1, n2 = args.tiny
                        t1 = timed(be, spec("tiny-a", n1, 1e-3), folder)
                        t2 = timed(be, spec("tiny-b", n2, 1e-3), folder)
                        overhead.setdefault(be_name, []).append((t2 - t1) / (n2 - n1))
                    be.close()
                    rates.setdefault((be_name, w), []).append(args.runs / wall)
                    print(
                        f"{rnd + 1:>5} {be_name:<8} {w:>7} {startup:>10.2f} {wall:>8.2f} {args.runs / wall:>8.3f} {os.getloadavg()[0]:>5.2f}",
                        flush=True,
                    )
    print("-" * 58)
    print(f"\nbest of {args.repeat} rounds:\n")
    print(f"{'backend':<8} {'workers':>7} {'runs/s':>8} {'s/run/worker':>13} {'efficiency':>11}")
    print("-" * 51)
    for (be_name, w), r in rates.items():
        best = max(r)
        base = max(rates[(be_name, 1)]) if (be_name, 1) in rates else None
        eff = f"{best / (w * base):.2f}" if base else "-"
        print(f"{be_name:<8} {w:>7} {best:>8.3f} {w / best:>13.3f} {eff:>11}")
    print("-" * 51)
    print("efficiency: rate(n) / (n x rate(1)) of the same backend, best rounds, measured above; raw: n plain processes")
    print("running the same simulations without qprr.campaign (what the machine allows)")
    for be_name in backends:
        for w in args.workers:
            if w > 1 and ("raw", w) in rates:
                e_be = max(rates[(be_name, w)]) / (w * max(rates[(be_name, 1)]))
                e_raw = max(rates[("raw", w)]) / (w * max(rates[("raw", 1)]))
                print(f"{be_name}, {w} workers: efficiency {e_be:.2f} = {e_be / e_raw:.2f} x the raw processes' {e_raw:.2f}")
    best_o = {k: min(v) for k, v in overhead.items()}
    for be_name, o in best_o.items():
        print(f"per-run overhead, {be_name}: {1e3 * o:.2f} ms per task round trip (tiny runs, 1 worker)")
    if "dask" in best_o:
        run_s = 1.0 / max(rates[("local", 1)])
        print(
            f"Dask path - local path: {1e3 * (best_o['dask'] - best_o['local']):+.2f} ms per run "
            f"({100 * (best_o['dask'] - best_o['local']) / run_s:+.2f} % of a {args.duration:g} s run)"
        )
    for (be_name, w), r in rates.items():
        if be_name != "raw" and ("raw", w) in rates:
            print(f"ratio {be_name} / raw processes, {w} workers: {max(r) / max(rates[('raw', w)]):.2f} of the machine's rate")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
