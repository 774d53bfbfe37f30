"""Simulation speed as ratios measured in the same run: vs the thesis's Simulink times and vs a bare Pinocchio loop.

    python benchmarks/sim_benchmark.py [--repeat 5] [--quick]

``--quick``: a smoke run of a few seconds: static-idc only, 2 s flights instead of 30 s (the thesis's
time scaled to 2 s), 1 s closed loops, one round, midpoint only.

1. Every 30 s flight scenario of Thesis Sec. 6.3 at 1 kHz, checked first (status ok, position RMSE
   < 0.3 m), then timed ``repeat`` times: median / min / max wall time on this machine and the
   ratio to the thesis's run time (Table 6.3 text: Matlab 2018, Intel Core i7 3.4 GHz; 14 min for
   the IDC, 25 min for the "MPC" (our desired-state inverse dynamics), 11 min for the MFC).
2. The cost of one closed-loop step (controller, allocation, logging, plant) next to the cost of
   one step of a bare loop: Pinocchio's ABA and the same integrator (the simulator's own stepper,
   a constant generalised force, nothing else), for idc, dsid and mfc and for each integrator.
   Their ratio is what the closed loop costs over the physics alone (issue 9).
3. Where a closed-loop step goes: the controller, timed inside the loop, and the rest.

Every row is printed when it completes.  Absolute numbers hold on this machine only (its CPU,
load and versions are printed first); the ratios are what carries to another machine.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import qprr
from qprr.dynamics import generalized_gravity
from qprr.scenarios import SCENARIOS
from qprr.sim import simulate
from qprr.sim.integrators import make_stepper
from qprr.thesis.missions import static_mission
from qprr.thesis.scenarios import THESIS_RUN_TIME_S, flight_controller

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/machine.py, wherever this runs from
from machine import machine_lines

FLIGHT = ("static-idc", "static-dsid", "static-mfc", "spiral", "noise", "pulses", "dynamic-bsg")
THESIS_FOR = {"static-idc": "idc", "static-dsid": "dsid", "static-mfc": "mfc", "spiral": "idc", "noise": "idc", "pulses": "idc", "dynamic-bsg": "mfc"}
"""Which of the thesis's three run times each scenario compares with (its controller)."""


def bare_loop_step(platform, integrator: str, n: int, dt: float = 1e-3) -> float:
    """Seconds per step of ABA + ``integrator`` alone: constant tau (gravity held), no controller, no logging."""
    model = platform.model
    data = model.createData()
    q = platform.neutral_q()
    q[2] = 5.0
    v = np.zeros(model.nv)
    tau = generalized_gravity(platform, data, q).copy()  # hover: the arm and base held by a constant force
    aba = pin.aba

    def f(t, q, v):
        return aba(model, data, q, v, tau)

    step = make_stepper(integrator, model, dt)
    t0 = time.perf_counter()
    for k in range(n):
        q, v, _ = step(f, k * dt, q, v)
    return (time.perf_counter() - t0) / n


def in_loop_controller_share(platform, name: str, seconds: float = 10.0, rounds: int = 3) -> tuple[float, float]:
    """(controller seconds per step, whole step seconds) in the static mission's closed loop (``seconds``), best of ``rounds``."""
    best = (float("inf"), float("inf"))
    clock = time.perf_counter
    for _ in range(rounds):
        ctrl = flight_controller(name, platform)
        inner = ctrl.step
        spent = [0.0]

        def timed(t, state, ref, inner=inner, spent=spent):
            t0 = clock()
            u = inner(t, state, ref)
            spent[0] += clock() - t0
            return u

        ctrl.step = timed  # the loop calls the instance's step
        res = simulate(platform, ctrl, static_mission(), seconds)
        if res.wall_time / res.n < best[1]:
            best = (spent[0] / res.n, res.wall_time / res.n)
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5, help="timed runs per scenario (after one checked run)")
    ap.add_argument("--quick", action="store_true", help="static-idc only, 2 s flights, 1 s loops, one round (a smoke run)")
    args = ap.parse_args(argv)
    if args.repeat < 1:
        ap.error("--repeat must be >= 1")
    scenarios = FLIGHT[:1] if args.quick else FLIGHT
    repeat = 1 if args.quick else args.repeat
    n_bare = 1000 if args.quick else 10000
    flight = 2.0 if args.quick else 30.0  # simulated seconds of a section-1 run
    loop_s, rounds = (1.0, 1) if args.quick else (10.0, 3)

    print("# qprr simulation benchmark\n")
    for line in machine_lines():
        print(f"- {line}")
    platform = qprr.load()
    print(f"\n## 1. Scenarios vs the thesis ({flight:g} s at 1 kHz, midpoint integrator; {repeat} timed runs after one checked run)\n")
    head = f"{'scenario':<13}{'ctrl':<6}{'median [s]':>11}{'min':>8}{'max':>8}{'thesis':>9}{'ours faster by':>16}"
    print(head)
    print("-" * len(head), flush=True)
    speedups = []
    for name in scenarios:
        sc = SCENARIOS[name]
        res = sc.run(platform=platform, duration=flight)
        e = res.rmse()
        if str(res.status) != "ok" or max(e["x"], e["y"], e["z"]) > 0.3:
            print(f"{name:<13} check failed: {res.status} ({res.reason}); position RMSE {e['x']:.2e}, {e['y']:.2e}, {e['z']:.2e} m")
            return 1
        times = [sc.run(platform=platform, duration=flight).wall_time for _ in range(repeat)]
        med = statistics.median(times)
        thesis = THESIS_RUN_TIME_S[THESIS_FOR[name]] * flight / 30.0  # the thesis's 30 s runs, per simulated second
        speedups.append(thesis / med)
        print(
            f"{name:<13}{sc.controllers[0]:<6}{med:>11.3f}{min(times):>8.3f}{max(times):>8.3f}{thesis / 60:>6.1f} min{thesis / med:>15.0f}x",
            flush=True,
        )
    print(f"\n(thesis: Simulink on a 2018 Core i7, its time scaled to {flight:g} s; ours: on this machine, the same simulated time)")
    print(f"ratio thesis time / ours, median over the scenarios: {statistics.median(speedups):.0f}")

    print("\n## 2. One step: closed loop vs a bare Pinocchio loop (ABA + the same integrator), measured alternately\n")
    head = f"{f'closed loop ({loop_s:g} s runs)':<28}{'per step [us]':>14}{'bare loop [us]':>16}{'ratio':>8}"
    print(head)
    print("-" * len(head), flush=True)
    rows = [("static-idc", "midpoint"), ("static-dsid", "midpoint"), ("static-mfc", "midpoint"), ("static-idc", "euler"), ("static-idc", "rk4")]
    rows = rows[:1] if args.quick else rows
    bare, ratios = {}, []
    for name, integ in rows:
        closed, base = [], []
        for _ in range(rounds):  # alternate: both see the same load
            r = SCENARIOS[name].run(platform=platform, integrator=integ, duration=loop_s)
            closed.append(r.wall_time / r.n)
            base.append(bare_loop_step(platform, integ, n_bare))
        c, b = min(closed), min(base)
        bare[integ] = min(bare.get(integ, b), b)
        label = f"{name} ({THESIS_FOR[name]}, {integ})"
        print(f"{label:<28}{1e6 * c:>14.1f}{1e6 * b:>16.1f}{c / b:>7.1f}x", flush=True)
        ratios.append(c / b)
    print(f"ratio closed loop / bare loop, {rows[0][0]} ({rows[0][1]}): {ratios[0]:.2f}")
    print(f"\n(best of {rounds} of each, alternated; ABA calls per step: euler 1, midpoint 2, rk4 4; the closed loop adds the")
    print(" controller, the allocation, the state conversions and the logs)")

    print(f"\n## 3. Where a closed-loop step goes (static mission, {loop_s:g} s, controller timed inside the loop)\n")
    for name in ("idc",) if args.quick else ("idc", "dsid", "mfc"):
        c, whole = in_loop_controller_share(platform, name, loop_s, rounds)
        print(
            f"{name:<5} controller {1e6 * c:5.1f} us ({100 * c / whole:2.0f} %) + the rest {1e6 * (whole - c):5.1f} us "
            f"(allocation, plant, logs) = {1e6 * whole:5.1f} us per step",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
