"""Closed-loop step cost against a bare Pinocchio step, in CPU instructions (valgrind): independent of the machine's load.

    python benchmarks/step_instructions.py                       # this checkout
    python benchmarks/step_instructions.py --tree /path/to/other/checkout    # e.g. an older commit:
        git worktree add /tmp/before <commit> && python benchmarks/step_instructions.py --tree /tmp/before

Wall-clock ratios (``sim_benchmark.py``) move by 10-15 % on a shared 2-core machine; instruction
counts do not. For each workload two durations are run under ``valgrind --tool=callgrind`` and
their difference divided by the number of extra steps (start-up cancels): instructions per
closed-loop step (controller, allocation, midpoint integration, logging) and per bare step
(two ABA calls and two ``pin.integrate`` of the same midpoint scheme, the same model, in the
same process setup, the robot held at rest by its gravity force: a falling arm would spin up and
make the trigonometry costlier from one tree to another). Their ratio is the closed loop's overhead over the plant alone. The cyclic
garbage collector is off in the measured runs: a full collection scans every object of every
imported module (its cost depends on what the process imported, not on the loop) and falls in
or out of the measured window by chance, which moved the counts by 10 %. Needs
valgrind (apt-get install valgrind); about 1 min per workload.  Without valgrind it says so and exits 0.

``--quick`` (a smoke run of a few seconds; valgrind's start-up alone costs about 40 s of CPU per run): the
same workloads run natively and timed inside the process (0.6 s minus 0.2 s of simulated time, after a
0.1 s warm-up): per-step wall-clock times and their ratio, not instruction counts.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ("static-idc", "static-mfc", "static-dsid")
THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
"""One thread each: idle BLAS threads spin, and valgrind would count their spinning (load-dependent)."""

SETUP = r"""
import sys
sys.path.insert(0, {tree!r})
import gc
import inspect
import numpy as np, pinocchio as pin
from qprr import load, scenarios
what, seconds = {what!r}, {seconds!r}
model = load().model
if "robot" in inspect.signature(scenarios.run).parameters:  # the Q-PRR-only API before the platform core
    robot = load()
    run = lambda name: scenarios.run(name, robot=robot, duration=seconds)
else:
    run = lambda name: scenarios.run(name, duration=seconds)
data = model.createData()
gc.disable()  # see the module docstring
"""
BARE = r"""dt, half = 1e-3, 0.5e-3
q = pin.neutral(model); q[2] = 5.0
v = np.zeros(model.nv); tau = pin.computeGeneralizedGravity(model, data, q).copy()  # held at rest: same work in every tree
for _ in range(int(round(seconds / dt))):
    a = pin.aba(model, data, q, v, tau)
    vh = v + half * a
    a2 = pin.aba(model, data, pin.integrate(model, q, half * v), vh, tau)
    q = pin.integrate(model, q, dt * vh)
    v = v + dt * a2
"""
WORKLOAD = SETUP + 'if what == "bare":\n' + textwrap.indent(BARE, "    ") + "else:\n    run(what)\n"
NATIVE = (
    SETUP
    + r"""import time


def workload():
    if what == "bare":
"""
    + textwrap.indent(BARE, "        ")
    + r"""    else:
        run(what)


workload()  # warm-up; then the difference of two timed runs in this process
short, long = 2 * seconds, 6 * seconds
clock = []
for seconds in (short, long):
    t0 = time.perf_counter()
    workload()
    clock.append(time.perf_counter() - t0)
print("per step", (clock[1] - clock[0]) / round((long - short) / 1e-3))
"""
)


def instructions(tree: Path, what: str, seconds: float) -> int:
    code = WORKLOAD.format(tree=str(tree), what=what, seconds=seconds)
    env = dict(os.environ, PYTHONHASHSEED="0", **{k: "1" for k in THREAD_VARS})
    proc = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd="/",
        env=env,
    )
    found = re.search(r"Collected : (\d+)", proc.stderr)
    if proc.returncode != 0 or found is None:
        raise SystemExit(f"valgrind run of {what!r} failed:\n{proc.stderr[-2000:]}")
    return int(found.group(1))


def per_step(tree: Path, what: str, short: float = 1.0, long: float = 3.0) -> float:
    steps = round((long - short) / 1e-3)
    return (instructions(tree, what, long) - instructions(tree, what, short)) / steps


def native_per_step(tree: Path, what: str, seconds: float = 0.1) -> float:
    """Wall-clock seconds per 1 ms step of a workload run natively (no valgrind): after a warm-up run of ``seconds``,
    the difference of runs of 6 and 2 x ``seconds`` in the same process, divided by the extra steps."""
    code = NATIVE.format(tree=str(tree), what=what, seconds=seconds)
    env = dict(os.environ, PYTHONHASHSEED="0", **{k: "1" for k in THREAD_VARS})
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd="/", env=env)
    found = re.search(r"per step ([0-9.eE+-]+)", proc.stdout)
    if proc.returncode != 0 or found is None:
        raise SystemExit(f"run of {what!r} failed:\n{proc.stderr[-2000:]}")
    return float(found.group(1))


def quick(tree: Path, scenarios) -> int:
    print(f"qprr tree: {tree}; {sys.executable}; --quick: native runs, wall-clock microseconds per 1 ms step (not instructions)")
    bare = native_per_step(tree, "bare")
    print(f"{'bare ABA + integrate (midpoint)':34s} {1e6 * bare:10.1f} us       1.00", flush=True)
    for name in scenarios:
        closed = native_per_step(tree, name)
        print(f"{name:34s} {1e6 * closed:10.1f} us ratio {closed / bare:5.2f}", flush=True)
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tree", type=Path, default=ROOT, help="checkout whose qprr is measured (default: this one)")
    parser.add_argument("--scenarios", nargs="+", default=None, help="closed loops to measure (default: all three; --quick: static-idc)")
    parser.add_argument("--quick", action="store_true", help="native runs timed by the clock, not valgrind (a smoke run)")
    args = parser.parse_args(argv)
    tree = args.tree.resolve()
    if args.quick:
        return quick(tree, args.scenarios or SCENARIOS[:1])
    if shutil.which("valgrind") is None:
        print("step_instructions: valgrind is not installed (apt-get install valgrind); nothing measured (--quick runs the workloads natively)")
        return 0
    print(f"qprr tree: {tree}; {sys.executable}; instructions per 1 ms step (difference of 3 s and 1 s runs)")
    bare = per_step(tree, "bare")
    print(f"{'bare ABA + integrate (midpoint)':34s} {bare:10.0f}        1.00", flush=True)
    for name in args.scenarios or SCENARIOS:
        closed = per_step(tree, name)
        print(f"{name:34s} {closed:10.0f} ratio {closed / bare:5.2f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
