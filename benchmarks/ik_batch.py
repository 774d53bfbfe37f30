"""Many IK targets in one call (qprr.ik.solve_many) against the same solves one by one, side by side in one run.

    python benchmarks/ik_batch.py [--platform borinot_flying_arm_2] [--n 400] [--workers 2] [--quick]

``--quick``: 24 targets (seconds; too few for a verdict: the worker processes' start dominates).

Targets: end-effector positions of random hover configurations (seeded), each solved cold from qprr's default guess.
Prints the wall time of the loop one by one, of ``solve_many(workers=1)`` and of ``solve_many(workers=N)`` (worker
processes started inside the timing), their ratios, and checks that the three gave the same answers.  Exits 0.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import qprr
from qprr.ik import IKSolver, solve_many
from qprr.ik.batch import reachable_targets


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--platform", default="borinot_flying_arm_2")
    ap.add_argument("--n", type=int, default=400)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="24 targets: the script runs in seconds")
    args = ap.parse_args()
    if args.quick:
        args.n = 24
    platform = qprr.build(args.platform) if args.platform.isupper() else qprr.load(args.platform)
    solver = IKSolver(platform)
    goals = reachable_targets(platform, args.n)
    data = platform.data()
    solver.solve(data, goals[0])  # warm-up: numba's kernels loaded or compiled before any timing
    t0 = time.perf_counter()
    one = [solver.solve(data, g) for g in goals]
    t1 = time.perf_counter()
    here = solve_many(solver, goals)
    t2 = time.perf_counter()
    spread = solve_many(solver, goals, workers=args.workers)
    t3 = time.perf_counter()
    same = all(
        a.status == b.status == c.status and np.array_equal(a.q, b.q) and np.array_equal(a.q, c.q)
        for a, b, c in zip(one, here.results, spread.results)
    )
    print(f"{args.n} cold targets on {platform.name}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    print(f"  one by one:                {t1 - t0:7.2f} s")
    print(f"  solve_many, workers=1:     {t2 - t1:7.2f} s  (speed ratio to one by one: {(t1 - t0) / (t2 - t1):.2f})")
    print(f"  solve_many, workers={args.workers}:     {t3 - t2:7.2f} s  (speed ratio to one by one: {(t1 - t0) / (t3 - t2):.2f})")
    print(f"  same answers: {same}; reached {int(spread.success.sum())} of {args.n}")


if __name__ == "__main__":
    main()
