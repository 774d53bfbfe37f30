"""Mobile-manipulation IK (qprr.wheeled.manipulation) on seeded random problems: robustness and cost.

For each arm (Q-PRR, 3R) on the car and each way of keeping the Pfaffian constraint
("equality": equality rows in every QP, the default; "nullspace": unknowns restricted to the
kernel), ``--runs`` random problems per seed: base pose in [-2, 2]^2 x [-pi, pi], steering in
[-0.6, 0.6] (30 % at a limit), arm inside its limits (30 % with a joint at a limit), target in
[-3, 3]^2 x [0.2, 1.0] m, 40 iterations at most.  Prints the outcome counts (a ProxQP failure is
"solver_error"), the largest slip of the applied base motions [m] and the wall time per IK
iteration.

    python benchmarks/wheeled_ik_benchmark.py [--runs 150] [--seeds 0 1 2]
"""

from __future__ import annotations

import argparse
import collections
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from machine import machine_lines

from qprr.wheeled.manipulation import car_scenario, solve_ik


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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=150)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    args = ap.parse_args(argv)
    print("\n".join(machine_lines()))
    print(f"{'arm':5s} {'elimination':11s} {'runs':>5s}  outcomes{'':38s} {'max slip [m]':>12s} {'us/iteration':>13s}")
    for arm in ("qprr", "3r"):
        mm = car_scenario(arm).robot
        for elim in ("equality", "nullspace"):
            counts, slip, per_iter = collections.Counter(), 0.0, []
            for seed in args.seeds:
                rng = np.random.default_rng(seed)
                for z0, target in problems(mm, rng, args.runs):
                    t0 = time.perf_counter()
                    r = solve_ik(mm, target, z0, {"max_iter": 40, "elimination": elim})
                    dt = time.perf_counter() - t0
                    counts[r.status.value] += 1
                    slip = max(slip, r.slip)
                    if r.iterations:
                        per_iter.append(1e6 * dt / r.iterations)
            outcome = ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
            print(f"{arm:5s} {elim:11s} {sum(counts.values()):5d}  {outcome:46s} {slip:12.1e} {statistics.median(per_iter):13.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
