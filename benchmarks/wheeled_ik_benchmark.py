"""Mobile-manipulation IK (qprr.wheeled.manipulation.solve_ik) on seeded random problems: success and cost.

For each arm (Q-PRR, 3R) on the car, ``--runs`` random problems per seed: base pose in
[-2, 2]^2 x [-pi, pi], steering in [-0.6, 0.6] (30 % at a limit), arm inside its limits (30 %
with a joint at a limit), target in [-3, 3]^2 x [0.2, 1.0] m; ``--max-iter`` IK iterations at
most (default: solve_ik's 400); ``--options``: options of solve_ik (a JSON dict).  Prints the
success rate (status "converged"), the outcome counts (a QP failure is "solver_error"), the IK
iterations of the converged runs (median, 90th percentile), the wall time per solve (median over
the converged runs, and over all runs) and per IK iteration, the largest Pfaffian residual
|E dz| of a QP step and the largest slip of the applied base motions [m].

``--against REV`` also runs the ``solve_ik`` of ``qprr/wheeled/manipulation.py`` as it was at the
git revision REV (loaded from git into the current package, so its own imports must still
exist), on the same problems, interleaved problem by problem with the current one (same machine
load), with ``--against-options`` (a JSON dict) as its options.  Each ``--options`` or
``--against-options`` adds a row.  The last line of each arm counts the problems where every
row succeeds or every row fails, and those where every row ends with the same status.

    python benchmarks/wheeled_ik_benchmark.py [--runs 20] [--seeds 0 1 2] [--max-iter 400] [--options '{"polish": false}']
                                              [--against 646d1ac [--against-options '{"elimination": "nullspace"}']]
                                              [--quick]

The last line gives the ratio of the median time per solve of the two arms (3R / Q-PRR), measured
side by side.  ``--quick``: 3 problems of one seed per arm, a smoke run of a few seconds.
"""

from __future__ import annotations

import argparse
import collections
import json
import subprocess
import sys
import time
import types
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines

from qprr.wheeled import manipulation

ROOT = Path(__file__).resolve().parents[1]


def module_at(rev: str) -> types.ModuleType:
    """qprr.wheeled.manipulation as it was at git revision ``rev``, executed inside the current package."""
    src = subprocess.run(["git", "-C", str(ROOT), "show", f"{rev}:qprr/wheeled/manipulation.py"], capture_output=True, text=True, check=True).stdout
    mod = types.ModuleType(f"qprr.wheeled._manipulation_at_{rev}")
    mod.__package__ = "qprr.wheeled"
    sys.modules[mod.__name__] = mod  # dataclasses look their module up there
    exec(compile(src, f"{rev}:qprr/wheeled/manipulation.py", "exec"), mod.__dict__)
    return mod


def problems(mm, rng, n):
    for _ in range(n):
        z0 = mm.neutral(rng.uniform([-2, -2, -np.pi], [2, 2, np.pi]))
        z0[3] = rng.uniform(-0.6, 0.6)
        z0[4:] = rng.uniform(mm.lower[4:], mm.upper[4:])
        if rng.random() < 0.3:
            z0[3] = rng.choice([-0.6, 0.6])
        if rng.random() < 0.3:
            j = rng.integers(4, 7)
            z0[j] = rng.choice([mm.lower[j], mm.upper[j]])
        yield z0, rng.uniform([-3, -3, 0.2], [3, 3, 1.0])


class Tally:
    def __init__(self):
        self.status, self.iters, self.t_ok, self.t_all, self.per_iter = collections.Counter(), [], [], [], []
        self.qp_res = self.slip = 0.0

    def add(self, r, dt):
        self.status[r.status.value] += 1
        self.t_all.append(dt)
        if r.status.value == "converged":
            self.iters.append(r.iterations)
            self.t_ok.append(dt)
        if r.iterations:
            self.per_iter.append(dt / r.iterations)
        self.qp_res = max(self.qp_res, float(np.max(r.qp_residual, initial=0.0)))
        self.slip = max(self.slip, r.slip)

    def row(self, arm, label):
        n = sum(self.status.values())
        ok = self.status["converged"]
        it = f"{np.median(self.iters):5.0f} {np.percentile(self.iters, 90):5.0f}" if self.iters else f"{'-':>5s} {'-':>5s}"
        t_ok = f"{1e3 * np.median(self.t_ok):8.1f}" if self.t_ok else f"{'-':>8s}"
        outcome = ", ".join(f"{k} {v}" for k, v in sorted(self.status.items()))
        return (
            f"{arm:5s} {label:34s} {n:5d} {100 * ok / n:6.1f}% {it} {t_ok} {1e3 * np.median(self.t_all):8.1f} "
            f"{1e6 * np.median(self.per_iter):8.0f} {self.qp_res:9.1e} {self.slip:8.1e}  {outcome}"
        )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=20, help="problems per seed and arm")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--max-iter", type=int, default=manipulation.MobileIKOptions().max_iter)
    ap.add_argument("--options", action="append", help="JSON options of the current solve_ik (repeat: one row each)")
    ap.add_argument("--against", metavar="REV", help="git revision whose solve_ik runs side by side")
    ap.add_argument("--against-options", action="append", help="JSON options of the --against solve_ik (repeatable)")
    ap.add_argument("--quick", action="store_true", help="3 problems of seed 0 per arm (a smoke run)")
    args = ap.parse_args(argv)
    if args.quick:
        args.runs, args.seeds = 3, [0]
    print("\n".join(machine_lines()))

    def label(name, extra):
        return f"{name} {' '.join(f'{k}={v}' for k, v in extra.items())}".strip()

    solvers = {}
    for opts in args.options or ["{}"]:
        extra = json.loads(opts)
        solvers[label("current", extra)] = (manipulation, {"max_iter": args.max_iter, **extra})
    if args.against:
        old = module_at(args.against)
        for opts in args.against_options or ["{}"]:
            extra = json.loads(opts)
            solvers[label(args.against, extra)] = (old, {"max_iter": args.max_iter, **extra})
    first = next(iter(solvers))
    print(f"{len(args.seeds)} seeds x {args.runs} problems per arm, at most {args.max_iter} IK iterations")
    print(
        f"{'arm':5s} {'solve_ik':34s} {'runs':>5s} {'success':>7s} {'iterations':>11s} {'ms/solve':>17s} "
        f"{'us/iter':>8s} {'max|E dz|':>9s} {'max slip':>8s}  outcomes"
    )
    print(f"{'':5s} {'':34s} {'':5s} {'':7s} {'med':>5s} {'p90':>5s} {'converged':>8s} {'all':>8s}")
    per_solve = {}
    for arm in ("qprr", "3r"):
        scen = {k: mod.car_scenario(arm).robot for k, (mod, _) in solvers.items()}
        tally = {k: Tally() for k in solvers}
        agree = agree_success = 0
        for seed in args.seeds:
            rng = np.random.default_rng(seed)
            for z0, target in problems(scen[first], rng, args.runs):
                st, ok = set(), set()
                for k, (mod, opts) in solvers.items():
                    t0 = time.perf_counter()
                    r = mod.solve_ik(scen[k], target, z0, opts)
                    tally[k].add(r, time.perf_counter() - t0)
                    st.add(r.status.value)
                    ok.add(r.success)
                agree += len(st) == 1
                agree_success += len(ok) == 1
        for k in solvers:
            print(tally[k].row(arm, k))
        per_solve[arm] = float(np.median(tally[first].t_all))
        if len(solvers) > 1:
            n = sum(tally[first].status.values())
            print(
                f"{arm:5s} problems where every row converges or every row fails: {agree_success} of {n}; "
                f"where every row ends with the same status: {agree} of {n}"
            )
        sys.stdout.flush()
    print(f"ratio of the median times per solve ({first}), 3r / qprr arm: {per_solve['3r'] / per_solve['qprr']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
