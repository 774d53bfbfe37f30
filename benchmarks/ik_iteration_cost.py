"""The QP IK's cost per Newton iteration on the Q-PRR's cold starts (docs/ik.md, issue 36).

    python benchmarks/ik_iteration_cost.py [--n 100] [--old DIR] [--quick]

Per iteration = (mean time of a cold start - mean time of the IGM start) / (mean iteration count - 1): the IGM start
is a solve whose start is already the answer (the fixed cost of a solve, the IGM included).  Four levels (the
default hierarchy) and pink's problem (two levels: pose, then hover), from the thesis guess; each target solved 5
times and the fastest kept, the garbage collector off, this thread's CPU time.  On this tree with each lexicographic
kernel installed ("numpy", and "numba" when numba is); ``--old DIR``: the same measurement on another source tree (a
checkout before a change) in a subprocess right after, with its default settings.  Prints the ratios of the costs per
iteration to the numpy kernel's.  ``--quick``: 12 targets (seconds once numba's kernel is compiled and cached).
"""

from __future__ import annotations

import argparse
import gc
import json
import subprocess
import sys
import time
from importlib.util import find_spec
from pathlib import Path

import numpy as np
import pinocchio as pin


def measure(n: int, kernel: str | None) -> dict:
    """Mean times [us] and iteration counts of the three solves, and the per-iteration costs, for ``n`` targets."""
    import qprr
    from qprr.ik.solver import IKSolver
    from qprr.ik.tasks import HoverTask, PoseTask
    from qprr.thesis import igm

    robot = qprr.load("q-prr")
    data = robot.data()
    rng = np.random.default_rng(0)
    targets = []
    for _ in range(n):  # random in-limit hover configurations (as benchmarks/ik_benchmark.py draws them)
        xi = np.zeros(9)
        xi[0:2] = rng.uniform(-3.0, 3.0, 2)
        xi[2] = rng.uniform(0.5, 3.0)
        xi[5] = rng.uniform(-np.pi, np.pi)
        xi[6:9] = rng.uniform(robot.arm_lower, robot.arm_upper)
        q = qprr.charts.xi_to_q(xi)
        pin.framesForwardKinematics(robot.model, data, q)
        targets.append(data.oMf[robot.ee_frame].copy())
    options = None if kernel is None else {"kernel": kernel}
    cold = igm.solver(robot, "qp", options, init="guess")
    start = igm.solver(robot, "qp", options, init="igm")
    pose = PoseTask(robot, pin.SE3.Identity())
    two = IKSolver(robot, "qp", {"levels": [[pose], [HoverTask()]], **(options or {})})

    def two_levels(M):
        pose.set_target(M)
        return two.solve(data, M, igm.hover_guess(robot.params, M.translation, M.rotation))

    out = {}
    for name, solve in (("igm start", lambda M: start.solve(data, M)), ("four levels", lambda M: cold.solve(data, M)), ("two levels", two_levels)):
        for M in targets[:10]:  # warm-up (numba loads or compiles its kernel here)
            solve(M)
        times, iterations = [], []
        gc.disable()
        try:
            for M in targets:
                best = np.inf
                for _ in range(5):
                    t0 = time.thread_time()
                    result = solve(M)
                    best = min(best, time.thread_time() - t0)
                times.append(best)
                iterations.append(result.iterations)
        finally:
            gc.enable()
        out[name] = (1e6 * float(np.mean(times)), float(np.mean(iterations)))
    fixed = out["igm start"][0]
    for name in ("four levels", "two levels"):
        t, it = out[name]
        out[name] += ((t - fixed) / max(it - 1.0, 1.0),)
    return out


def report(label: str, out: dict, ref: dict | None = None) -> None:
    """One line per tree and kernel; with ``ref``, the ratio of ref's cost per iteration to this one's."""
    t_fixed = out["igm start"][0]
    print(f"- {label}: IGM start {t_fixed:.0f} us", end="")
    for name in ("four levels", "two levels"):
        t, it, per = out[name]
        print(f"; {name} {t:.0f} us, {it:.2f} iterations, {per:.0f} us per iteration", end="")
        if ref is not None:
            print(f" (ratio to the numpy kernel's: {ref[name][2] / per:.2f}x faster)", end="")
    print(flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="targets")
    ap.add_argument("--old", type=Path, default=None, help="another source tree, measured in a subprocess after this one")
    ap.add_argument("--quick", action="store_true", help="12 targets")
    ap.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # the subprocess's answer
    args = ap.parse_args(argv)
    if args.quick:
        args.n = 12
    if args.json:
        print(json.dumps(measure(args.n, None)))
        return 0
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from machine import machine_lines

    for line in machine_lines(("numba",)):
        print(f"- {line}")
    reference = measure(args.n, "numpy")
    report("this tree, kernel 'numpy'", reference, reference)
    if find_spec("numba") is not None:
        report("this tree, kernel 'numba'", measure(args.n, "numba"), reference)
    else:
        print("- kernel 'numba': numba is not installed: pip install 'qprr[fast]'")
    if args.old is not None:
        env_path = str(args.old.resolve())
        cmd = [sys.executable, str(Path(__file__).resolve()), "--json", "--n", str(args.n)]
        run = subprocess.run(cmd, capture_output=True, text=True, check=True, cwd=env_path, env={"PYTHONPATH": env_path, "PATH": "/usr/bin:/bin"})
        report(f"{env_path} (its defaults)", json.loads(run.stdout.strip().splitlines()[-1]), reference)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
