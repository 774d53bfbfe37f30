"""Wall time of every 30 s flight scenario at 1 kHz, next to the thesis's Simulink run times.

Thesis, Table 6.3 text (Matlab 2018, Intel Core i7 3.4 GHz): T_x = 14 min for the IDC, 25 min
for the "MPC" (our desired-state inverse dynamics), 11 min for the MFC.  Target here: every
30 s scenario <= 1.0 s.

    python benchmarks/sim_benchmark.py [--repeat 7]

Prints the machine, checks each run before timing it (status ok, RMSE bounded), then the
median / min / max wall time of ``repeat`` runs, the ratio to the thesis's time, a per-step
breakdown and the integrator costs.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import timeit
from pathlib import Path

import numpy as np

from qprr import load
from qprr.control import make_controller
from qprr.control.base import Controller, Reference, State
from qprr.coordinates import xi_to_qv
from qprr.scenarios import SCENARIOS, THESIS_RUN_TIME_S, run
from qprr.sim import simulate
from qprr.trajectory import Hold

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/machine.py, wherever this runs from
from machine import machine_lines

THESIS_FOR = {"static-idc": "idc", "static-dsid": "dsid", "static-mfc": "mfc", "spiral": "idc", "noise": "idc",
              "pulses": "idc", "dynamic-bsg": "mfc"}
TARGET_S = 1.0


def machine() -> str:
    return " | ".join(machine_lines())


class _Hover(Controller):
    name = "open-loop"

    def __init__(self, u):
        self.u = u

    def step(self, t, state, ref):
        return self.u


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    robot = load()
    print(machine())
    print(f"scenarios: 30 s at 1 kHz (30,000 steps), midpoint integrator; {args.repeat} timed runs each after one warm-up\n")

    # warm-up and correctness first
    for name in SCENARIOS:
        res = run(name, robot=robot)
        e = res.rmse()
        if res.status != "ok" or max(e["x"], e["y"], e["z"]) > 0.3:
            print(f"CHECK FAILED for {name}: {res.status} {res.reason} {e}")
            return 1
    print("correctness: every scenario completes, position RMSE < 0.3 m\n")

    header = f"{'scenario':<13}{'ctrl':<9}{'median s':>9}{'min s':>8}{'max s':>8}{'thesis':>8}{'ratio':>8}  target {TARGET_S:.1f} s"
    print(header)
    print("-" * len(header))
    worst = 0.0
    for name in SCENARIOS:
        times = [run(name, robot=robot).wall_time for _ in range(args.repeat)]
        med = statistics.median(times)
        worst = max(worst, med)
        th = THESIS_RUN_TIME_S[THESIS_FOR[name]]
        ok = "ok" if med <= TARGET_S else "OVER"
        print(f"{name:<13}{SCENARIOS[name].controller:<9}{med:>9.3f}{min(times):>8.3f}{max(times):>8.3f}"
              f"{th / 60:>6.0f}min{th / med:>8.0f}x  {ok}")
    print("-" * len(header))
    print(f"worst median {worst:.3f} s: {'meets' if worst <= TARGET_S else 'misses'} the {TARGET_S:.1f} s target\n")

    # per-step breakdown
    xi = np.r_[0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    u = np.zeros(9)
    u[2] = robot.params.total_mass * robot.params.g  # hover at the zero pose: u = G(xi)
    sim_only = statistics.median([simulate(robot, _Hover(u), Hold(tuple(xi)), 30.0).wall_time for _ in range(3)])
    print(f"simulator alone (open-loop controller, midpoint, logging): {sim_only / 30e3 * 1e6:.1f} us/step")
    st = State()
    q, v = xi_to_qv(xi, np.full(9, 0.01))
    st.update(0.0, q, v)
    for cname in ("idc", "dsid", "mfc"):
        c = make_controller(cname, robot)
        ref = Reference(xi + 0.01, np.zeros(9), np.zeros(9))  # a state off its reference
        c.reset(st, ref, 1e-3)
        n = 20000
        us = timeit.timeit(lambda c=c, ref=ref: c.step(0.0, st, ref), number=n) / n * 1e6
        print(f"controller {cname}.step: {us:.1f} us")
    for integ in ("euler", "midpoint", "rk4"):
        ts = [run("static-idc", robot=robot, integrator=integ).wall_time for _ in range(3)]
        print(f"static-idc with integrator {integ:<9}: median {statistics.median(ts):.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
