"""Campaign throughput: runs per second with 1, 2, ... workers, locally and on a Dask LocalCluster.

    python benchmarks/campaign_benchmark.py [--runs 16] [--duration 30] [--workers 1 2] [--no-dask]

* Throughput: a campaign of ``--runs`` runs of the ``static-idc`` scenario (``--duration`` s
  at 1 kHz, a random +-10 % mass error per run so that no two runs are alike) on each backend and
  worker count.  Each backend is started and warmed up first (worker processes spawned, qprr
  imported, one short run per worker), then the campaign is timed: the rate is steady-state
  throughput, startup excluded (startup is printed apart).
* Parallel efficiency: rate with n workers / (n x the rate with 1 worker of the same backend),
  all measured in this one run, side by side.
* Per-run overhead of the Dask path against the local one: campaigns of tiny runs (one control
  tick) of two sizes on one worker; (time(N2) - time(N1)) / (N2 - N1) is the cost of one
  task's round trip (submit, pickle, run, return, save a row), startup cancelled out.

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
    return CampaignSpec.from_mapping({"name": name, "scenario": "static-idc", "seed": 1, "samples": runs,
                                      "options": {"duration": duration},
                                      "random": {"model.mass": {"dist": "uniform", "low": 0.9, "high": 1.1}}})


def timed(backend, sp: CampaignSpec, folder: Path) -> float:
    t0 = time.perf_counter()
    done = run_campaign(sp, folder / f"{sp.name}-{time.perf_counter_ns()}.csv", backend=backend, progress=False)
    wall = time.perf_counter() - t0
    bad = len(done.results) - int((done.results.table["status"] == "ok").sum())
    if done.executed != sp.n_runs or bad:
        raise SystemExit(f"benchmark campaign {sp.name}: {done.executed} runs, {bad} not ok")
    return wall


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=16, help="runs per timed campaign (default 16)")
    ap.add_argument("--duration", type=float, default=30.0, help="simulated seconds per run (default 30)")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2], help="worker counts (default 1 2)")
    ap.add_argument("--no-dask", action="store_true", help="local backend only")
    ap.add_argument("--tiny", type=int, nargs=2, default=[20, 220], metavar=("N1", "N2"),
                    help="sizes of the tiny-run campaigns for the per-run overhead (default 20 220)")
    args = ap.parse_args(argv)
    for line in machine_lines(("dask", "distributed")):
        print(line)
    backends = ["local"] + ([] if args.no_dask else ["dask"])
    print(f"\nthroughput: {args.runs} runs of static-idc, {args.duration:g} s at 1 kHz each (steady state, warmed-up workers)\n")
    print(f"{'backend':<8} {'workers':>7} {'startup s':>10} {'wall s':>8} {'runs/s':>8} {'s/run':>7} {'efficiency':>11}")
    print("-" * 65)
    rates: dict[tuple[str, int], float] = {}
    overhead: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for be_name in backends:
            for w in args.workers:
                t0 = time.perf_counter()
                be = make_backend(be_name, workers=w)
                timed(be, spec("warm-up", 2 * w, 0.01), folder)
                startup = time.perf_counter() - t0
                wall = timed(be, spec("throughput", args.runs, args.duration), folder)
                if w == 1:
                    n1, n2 = args.tiny
                    overhead[be_name] = (timed(be, spec("tiny-b", n2, 1e-3), folder) - timed(be, spec("tiny-a", n1, 1e-3), folder)) / (n2 - n1)
                be.close()
                rate = args.runs / wall
                rates[(be_name, w)] = rate
                base = rates.get((be_name, 1))
                eff = f"{rate / (w * base):.2f}" if base else "-"
                print(f"{be_name:<8} {w:>7} {startup:>10.2f} {wall:>8.2f} {rate:>8.3f} {wall * w / args.runs:>7.3f} {eff:>11}", flush=True)
    print("-" * 65)
    print("efficiency: rate(n) / (n x rate(1)) of the same backend, measured above")
    for be_name, o in overhead.items():
        print(f"per-run overhead, {be_name}: {1e3 * o:.2f} ms per task round trip (tiny runs, 1 worker)")
    if "dask" in overhead:
        print(f"Dask path - local path: {1e3 * (overhead['dask'] - overhead['local']):+.2f} ms per run "
              f"({100 * (overhead['dask'] - overhead['local']) / (1.0 / rates[('local', 1)]):+.2f} % of a {args.duration:g} s run)")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
