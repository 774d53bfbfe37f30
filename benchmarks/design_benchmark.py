"""Design-search throughput, parallel efficiency, where an evaluation's time goes, and pymoo vs Optuna.

    python benchmarks/design_benchmark.py [--designs 24] [--samples 10000] [--repeat 2] [--no-throughput]
                                          [--optimisers [--seeds 5] [--generations 8]]

* Throughput: ``--designs`` designs (the thesis study's architectures, cycled, each with its own
  reach so that no two are alike) at the default effort (``--samples`` per map) evaluated through
  :func:`qprr.design.run_design` on a local process pool of 1 and of 2 workers, each pool started
  and warmed up first (startup excluded); rounds interleaved, the best of ``--repeat`` kept.
  Prints designs per second per core and the parallel efficiency rate(2) / (2 rate(1)).
* CPU time (process time: robust to a shared machine) per map of one evaluation (inline): workspace, balance, hover, capacity, singularity;
  the share spent outside the maps (building the platform, the row) says whether batching the
  map kernels across designs could pay.
* The fixed part of an evaluation: CPU time at n/4, n and 4n samples per map, fitted by a + b n;
  a (per design, whatever the samples) is all that evaluating several designs in one batch of
  map kernels could save; b n is the map kernels' batched numpy work.
* ``--optimisers``: pymoo's NSGA2 and Optuna's NSGAIISampler on one small study (Q-PRR, reach,
  taper and slider stroke free; objectives hover volume (max) and arm mass (min); population 8,
  ``--generations`` (8), seeds 0..``--seeds`` - 1 (5)): the exact 2-D hypervolume of the feasible front after each
  generation (reference point: 0 m^3, 0.6 kg) and the optimiser's own time per evaluation (ask +
  tell, the evaluations excluded).

The machine is shared: the load average is printed before and after; measure when it is low.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np

from qprr.campaign import LocalBackend
from qprr.design import DesignSpec, run_design
from qprr.design.evaluate import evaluate_design
from qprr.design.search import hypervolume_2d, make_optimiser

ARCHS = ["Q-PRR", "Q-RPR", "Q-RRP", "Q-RR", "Q-RRR", "HEX-PRR", "HEX-RRR", "HEX-RR"]


def study(n: int, samples: int, offset: float = 0.0) -> DesignSpec:
    """``n`` designs: the architectures x distinct reaches (a grid)."""
    per = int(np.ceil(n / len(ARCHS)))
    reach = [round(0.22 + offset + 0.01 * k, 4) for k in range(per)]
    return DesignSpec.from_mapping(
        {
            "name": f"bench-{n}-{offset}",
            "architectures": ARCHS,
            "objectives": ["hover_volume", "arm_mass"],
            "parameters": {"reach": reach},
            "effort": {"samples": samples},
        }
    )


def throughput(args) -> None:
    rates = {1: 0.0, 2: 0.0}
    pools = {w: LocalBackend(w) for w in (1, 2)}
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for w, be in pools.items():  # warm-up: spawn, import, one design per worker
                run_design(study(2 * w, 500, offset=0.5), Path(tmp) / f"warm{w}.csv", backend=be, progress=False)
            for r in range(args.repeat):
                for w, be in pools.items():
                    spec = study(args.designs, args.samples, offset=0.001 * r)
                    n = len(spec.architectures) * len(spec.parameters["reach"].values)
                    t0 = time.perf_counter()
                    run_design(spec, Path(tmp) / f"r{r}w{w}.csv", backend=be, progress=False)
                    rate = n / (time.perf_counter() - t0)
                    print(f"  round {r + 1}: {w} worker(s): {n} designs, {rate:.3f} designs/s")
                    rates[w] = max(rates[w], rate)
    finally:
        for be in pools.values():
            be.close()
    print(f"designs per second per core at {args.samples} samples per map: {rates[1]:.3f} (1 worker), {rates[2] / 2:.3f} (2 workers)")
    print(f"parallel efficiency on 2 workers: {rates[2] / (2 * rates[1]):.3f} (target >= 0.85)")
    print(f"ratio of the 2-worker to the 1-worker throughput: {rates[2] / rates[1]:.2f} (ideal 2)")


def split(args) -> None:
    from qprr.analysis import balance, capacity, hover, singularity, workspace
    from qprr.design.evaluate import Candidate, build_candidate, slider_of
    from qprr.design.search import fixed_params

    spec = study(8, args.samples)
    params = fixed_params(spec)
    warm = {"run": 0, "seed": 0, "kind": "grid", "architecture": "Q-RR", "name": "Q-RR", "generation": -1, "params": {**params, "reach": 0.2}}
    evaluate_design(spec.to_dict(), warm)  # imports and first-call costs out of the way
    for arch in ("Q-PRR", "HEX-RRR"):
        t = {}
        t0 = time.process_time()
        p = build_candidate(Candidate(arch, {**params, "reach": 0.28}), spec.mass)
        t["build"] = time.process_time() - t0
        n = args.samples
        for name, fn, kw in (
            ("workspace", workspace, {"variants": []}),
            ("balance", balance, {"slider": slider_of(p), "tol": 1e-3}),
            ("hover", hover, {}),
            ("capacity", capacity, {}),
            ("singularity", singularity, {"task": "position"}),
        ):
            t0 = time.process_time()
            fn(p, n_samples=n, **kw)
            t[name] = time.process_time() - t0
        point = {"run": 0, "seed": 0, "kind": "grid", "architecture": arch, "name": arch, "generation": -1, "params": {**params, "reach": 0.28}}
        t0 = time.process_time()
        evaluate_design(spec.to_dict(), point)
        total = time.process_time() - t0
        maps = sum(v for k, v in t.items() if k != "build")
        print(
            f"{arch}: one evaluation {total:.3f} s = maps {maps:.3f} s ("
            + ", ".join(f"{k} {v:.3f}" for k, v in t.items() if k != "build")
            + f") + build {t['build']:.3f} s + other {max(total - maps - t['build'], 0.0):.3f} s"
        )


def fixed_cost(args) -> None:
    """t(n) = a + b n fitted over n/4, n, 4n samples per map: a is what batching designs together could save."""
    from qprr.design.search import fixed_params

    spec = study(8, args.samples)
    params = fixed_params(spec)
    ns = [args.samples // 4, args.samples, 4 * args.samples]
    for arch in ("Q-PRR", "HEX-RRR"):
        ts = []
        for n in ns:
            sp = DesignSpec.from_mapping({**spec.to_dict(), "effort": {**spec.to_dict()["effort"], "samples": n}})
            point = {"run": 0, "seed": 0, "kind": "grid", "architecture": arch, "name": arch, "generation": -1, "params": {**params, "reach": 0.28}}
            best = np.inf
            for _ in range(2):
                t0 = time.process_time()
                evaluate_design(sp.to_dict(), point)
                best = min(best, time.process_time() - t0)
            ts.append(best)
        b, a = np.polyfit(ns, ts, 1)
        print(
            f"{arch}: CPU time per evaluation at {ns} samples: "
            + ", ".join(f"{t:.3f}" for t in ts)
            + f" s; fixed part {a:.3f} s = {100 * a / (a + b * args.samples):.0f} % at {args.samples} samples "
            f"(the most batching designs together could save)"
        )


def optimisers(args) -> None:
    base = {
        "name": "opt",
        "architectures": ["Q-PRR"],
        "objectives": ["hover_volume", "arm_mass"],
        "effort": {"samples": 2000},
        "parameters": {"reach": {"low": 0.15, "high": 0.45}, "taper": {"low": 0.3, "high": 1.5}, "slider_stroke": {"low": 0.02, "high": 0.16}},
        "search": {"method": "nsga2", "population": 8, "generations": args.generations},
    }
    spec = DesignSpec.from_mapping(base)
    names = spec.optimised
    lo = [spec.parameters[k].low for k in names]
    hi = [spec.parameters[k].high for k in names]
    fixed = {k: p.values[0] for k, p in spec.parameters.items() if not p.optimised}
    cache: dict[tuple, tuple] = {}
    for engine in ("pymoo", "optuna"):
        gens, seeds = args.generations, args.seeds
        hv = np.zeros((seeds, gens))
        own = []
        for seed in range(seeds):
            opt = make_optimiser(engine, lo, hi, 2, 1, 8, seed)
            pts = []
            t_opt = 0.0
            for g in range(gens):
                t0 = time.process_time()
                X = opt.ask()
                t_opt += time.process_time() - t0
                F = np.empty((8, 2))
                for k, x in enumerate(X):
                    key = tuple(np.round(x, 12))
                    if key not in cache:
                        row = evaluate_design(
                            spec.to_dict(),
                            {
                                "run": 0,
                                "seed": 0,
                                "kind": "nsga2",
                                "architecture": "Q-PRR",
                                "name": "Q-PRR",
                                "generation": g,
                                "params": {**fixed, **dict(zip(names, map(float, x)))},
                            },
                        )
                        cache[key] = (-row["hover_volume"], row["arm_mass"])
                    F[k] = cache[key]
                pts.append(F)
                t0 = time.process_time()
                opt.tell(F, -np.ones((8, 1)))
                t_opt += time.process_time() - t0
                hv[seed, g] = hypervolume_2d(np.vstack(pts), (0.0, 0.6))
            own.append(t_opt / (8 * gens))
        m = hv.mean(axis=0)
        print(
            f"{engine}: hypervolume [m^3 kg] after 8, 16, ..., {8 * gens} evaluations (mean of {seeds} seeds): "
            + ", ".join(f"{v:.5f}" for v in m)
            + f"; worst / best seed at {8 * gens}: {hv[:, -1].min():.5f} / {hv[:, -1].max():.5f}; "
            f"optimiser time per evaluation {1e3 * np.mean(own):.2f} ms"
        )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--designs", type=int, default=24)
    ap.add_argument("--samples", type=int, default=dataclasses.fields(__import__("qprr.design.spec", fromlist=["Effort"]).Effort)[0].default)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--optimisers", action="store_true")
    ap.add_argument("--no-throughput", action="store_true")
    ap.add_argument("--seeds", type=int, default=5, help="optimiser comparison: seeds per engine")
    ap.add_argument("--generations", type=int, default=8, help="optimiser comparison: generations of 8")
    ap.add_argument("--quick", action="store_true", help="4 designs at 400 samples, one round (the smoke run of the tests)")
    args = ap.parse_args()
    if args.quick:
        args.designs, args.samples, args.repeat = 4, 400, 1
    print(f"load average before: {os.getloadavg()}")
    split(args)
    fixed_cost(args)
    if not args.no_throughput:
        throughput(args)
    if args.optimisers:
        optimisers(args)
    print(f"load average after: {os.getloadavg()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
